"""Batch mapping on a long sequence: the sequence mapped in one process, then by the batch command
with 1 and 2 local workers, timed (wall, and CPU of every process involved), and the merged maps
compared with the one-process map.

    python python/tools/batch_long.py DATA [--scans N] [--chunk-size 40] [--set max_range=50]

DATA is a SemanticKITTI-layout sequence with its classes.yaml (e.g. one `evidential_octomap
generate` wrote: SYNTHETIC). Prints a markdown table and the load average before each run.
"""
import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

import evidential_octomap as eo
from evidential_octomap import batch


def cpu_s():
    """User + system CPU of this process and of its finished children [s]."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def load():
    return " ".join(open("/proc/loadavg").read().split()[:3])


def timed(run):
    wall, cpu = time.time(), cpu_s()
    result = run()
    return result, time.time() - wall, cpu_s() - cpu


def differences(reference, tree):
    """Leaves, and leaf centres of the reference whose label or occupied state differ in `tree`."""
    leaves = reference.leaves()
    got = tree.query(leaves.centers)
    return (tree.num_leaves, int((got.labels != leaves.labels).sum()),
            int((got.occupied != (leaves.occupancy > 0.5)).sum()))


def main():
    p = argparse.ArgumentParser()
    p.add_argument("data")
    p.add_argument("--scans", type=int, default=0)
    p.add_argument("--chunk-size", type=int, default=40)
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    args = p.parse_args()
    classes = os.path.join(args.data, "classes.yaml")
    scans = args.scans or len(os.listdir(os.path.join(args.data, "velodyne")))
    config = batch.config_overrides(args.set)
    job = batch.MappingJob(data=args.data, classes=classes, config=config)
    rows = []
    print("load before one process:", load())
    sequential, wall, cpu = timed(lambda: batch.map_chunk(job, 0, scans).tree)
    rows.append(("one process (`batch.map_chunk`, OpenMP threads)", wall, cpu, "reference"))
    with tempfile.TemporaryDirectory() as tmp:
        for workers in (1, 2):
            out = os.path.join(tmp, "w%d.ot" % workers)
            command = [sys.executable, "-m", "evidential_octomap.batch", "--data", args.data,
                       "--classes", classes, "--out", out, "--scans", str(scans), "--chunk-size",
                       str(args.chunk_size), "--workers", str(workers), "-q"]
            for s in args.set:
                command += ["--set", s]
            print("load before %d worker(s):" % workers, load())
            _, wall, cpu = timed(lambda: subprocess.run(command, check=True))
            leaves, labels, occupied = differences(sequential, eo.load(out))
            rows.append(("batch, %d worker(s), chunks of %d" % (workers, args.chunk_size), wall, cpu,
                         "%d leaves (one process: %d); %d leaf labels and %d occupied states differ"
                         % (leaves, sequential.num_leaves, labels, occupied)))
    print("load after:", load())
    print("\n| run (%d scans) | wall s | CPU s | merged map against the one-process map |" % scans)
    print("|---|---|---|---|")
    for name, wall, cpu, note in rows:
        print("| %s | %.1f | %.1f | %s |" % (name, wall, cpu, note))


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
