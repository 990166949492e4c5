"""The tiled batch against one process on a long sequence: wall and CPU time, scans/s, the peak
RSS of every process (client, scheduler, each worker; in the first and the second half of the
scans mapped, so growth with the sequence shows), the task costs, and the streamed global map
compared with the one-process map leaf by leaf. Writes docs/experiments/scale_out.md.

    python python/tools/scale_out.py DATA [--scans N] [--chunk-size 25] [--set max_range=50]
        [--out docs/experiments/scale_out.md]

DATA is a SemanticKITTI-layout sequence with its classes.yaml (e.g. `evidential_octomap
generate` output: SYNTHETIC). The one-process map is batch.map_chunk over every scan (OpenMP
threads on every core), clamped once at the end as the batch's tiles are.
"""
import argparse
import datetime
import os
import re
import resource
import subprocess
import sys
import tempfile
import threading
import time

import numpy as np
import psutil

import evidential_octomap as eo

REFERENCE = """
import sys, dataclasses
from evidential_octomap import batch
job = batch.MappingJob(data=sys.argv[1], classes=sys.argv[2], unclamped=True,
                       config=batch.config_overrides(sys.argv[5:]))
tree = batch.map_chunk(job, 0, int(sys.argv[3])).tree
tree.clamp_occupancy()
tree.save(sys.argv[4])
"""


def load():
    return " ".join(open("/proc/loadavg").read().split()[:3])


def children_cpu():
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return kids.ru_utime + kids.ru_stime


class Monitor:
    """Samples the RSS of a process and its descendants every 0.2 s; splits each one's peak at
    the moment half of the scans are mapped (read from the batch's progress line)."""

    def __init__(self, process: subprocess.Popen, scans: int):
        self.root, self.scans = psutil.Process(process.pid), scans
        self.mapped = 0
        self.peaks = {}  # pid -> [role, peak in first half, peak in second half]
        self.stop = threading.Event()
        self.threads = [threading.Thread(target=self.sample),
                        threading.Thread(target=self.read, args=(process.stderr,))]
        for t in self.threads:
            t.start()

    def role(self, p):
        if p.pid == self.root.pid:
            return "client (and the local scheduler)"
        line = " ".join(p.cmdline())
        return "worker" if "spawn_main" in line or "worker" in line else "helper"

    def sample(self):
        while not self.stop.is_set():
            try:
                for p in [self.root] + self.root.children(recursive=True):
                    entry = self.peaks.setdefault(p.pid, [self.role(p), 0, 0])
                    half = 1 if self.mapped < self.scans / 2 else 2
                    entry[half] = max(entry[half], p.memory_info().rss)
            except psutil.Error:
                pass
            time.sleep(0.2)

    def read(self, stream):
        for chunk in iter(lambda: stream.read(256), ""):
            found = re.findall(r"(\d+)/\d+ scans mapped", chunk)
            if found:
                self.mapped = int(found[-1])

    def finish(self):
        self.stop.set()
        for t in self.threads:
            t.join()


def run_batch(args, classes, out, workers, threads):
    command = [sys.executable, "-m", "evidential_octomap.batch", "--data", args.data,
               "--classes", classes, "--out", out, "--global-map", out + ".ot",
               "--chunk-size", str(args.chunk_size), "--workers", str(workers),
               "--threads", str(threads)]
    if args.scans:
        command += ["--scans", str(args.scans)]
    for s in args.set:
        command += ["--set", s]
    wall, cpu = time.time(), children_cpu()
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    monitor = Monitor(process, args.scans)
    stdout = process.stdout.read()
    process.wait()
    monitor.finish()
    if process.returncode:
        raise SystemExit(f"batch failed: {' '.join(command)}")
    return time.time() - wall, children_cpu() - cpu, monitor.peaks, stdout


def same_bytes(a, b, block=1 << 24):
    with open(a, "rb") as fa, open(b, "rb") as fb:
        while True:
            x, y = fa.read(block), fb.read(block)
            if x != y:
                return False
            if not x:
                return True


def compare(reference, tiled_directory, streamed):
    """Leaves, labels and occupied states that differ, and the largest belief difference, tile
    by tile (the reference in memory once, one tile at a time beside it)."""
    if same_bytes(reference, streamed):
        return "identical bytes: 0 labels, 0 occupied states, 0 payload difference"
    whole = eo.load(reference)
    tiled = eo.TiledMap(tiled_directory)
    leaves = labels = occupied = 0
    belief = 0.0
    for tile in tiled.tiles:
        part = tiled.load_tile(tile).leaves()
        got = tiled.query(part.centers)
        want = whole.query(part.centers)
        leaves += len(part.centers)
        labels += int((got.labels != want.labels).sum())
        occupied += int((got.occupied != want.occupied).sum() + (~want.known).sum())
        belief = max(belief, float(np.abs(got.belief - want.belief).max(initial=0.0)))
    return (f"{leaves} leaves (one process {whole.num_leaves}); {labels} labels and {occupied} "
            f"occupied states differ; largest belief difference {belief:.2g}")


def main():
    p = argparse.ArgumentParser()
    p.add_argument("data")
    p.add_argument("--scans", type=int, default=0)
    p.add_argument("--chunk-size", type=int, default=25)
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    p.add_argument("--out", default="docs/experiments/scale_out.md")
    args = p.parse_args()
    classes = os.path.join(args.data, "classes.yaml")
    args.scans = args.scans or len(os.listdir(os.path.join(args.data, "velodyne")))
    cores = os.cpu_count()
    rows, loads = [], []
    with tempfile.TemporaryDirectory() as tmp:
        reference = os.path.join(tmp, "one_process.ot")
        loads.append(load())
        wall, cpu = time.time(), children_cpu()
        subprocess.run([sys.executable, "-c", REFERENCE, args.data, classes, str(args.scans),
                        reference] + args.set, check=True)
        wall, cpu = time.time() - wall, children_cpu() - cpu
        rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1e6
        rows.append((f"one process ({cores} OpenMP threads)", wall, cpu, f"{rss:.2f} (one process)",
                     "–", "reference", ""))
        for workers, threads in ((1, cores), (2, max(1, cores // 2))):
            out = os.path.join(tmp, f"w{workers}")
            loads.append(load())
            wall, cpu, peaks, stdout = run_batch(args, classes, out, workers, threads)
            tasks = re.search(r"task wall times: (.*)", stdout).group(1)
            rss = "; ".join(f"{role} {first / 1e9:.2f} / {second / 1e9:.2f}"
                            for role, first, second in sorted(peaks.values(), key=str)
                            if max(first, second) > 100e6)
            rows.append((f"batch, {workers} worker(s) × {threads} thread(s)", wall, cpu, rss,
                         tasks, compare(reference, out, out + ".ot"), ""))
        loads.append(load())
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True, cwd=os.path.dirname(os.path.abspath(__file__))).stdout.strip()
    readme = os.path.join(args.data, "README.md")
    title = open(readme).readline().strip("# \n") if os.path.exists(readme) else args.data
    settings = " ".join(f"--set {s}" for s in args.set)
    lines = ["# Scale-out: the tiled Dask batch against one process", "",
             f"Generated by `python/tools/scale_out.py DATA --scans {args.scans} --chunk-size "
             f"{args.chunk_size} {settings}` (commit {commit}, {datetime.date.today()}).", "",
             f"Data: {title} (SYNTHETIC), {args.scans} scans, 0.2 m, derived one-hot evidence. "
             f"Machine: {cores} cores shared with other jobs; load average before each run and "
             f"after the last: {'; '.join(loads)}. Peak RSS of a process over the first / the "
             "second half of the scans mapped (a process whose memory grew with the map would "
             "peak higher in the second half); processes under 100 MB left out.", "",
             "| run | wall s | CPU s | scans/s | peak RSS, GB (first / second half) | task wall "
             "times (mean × count) | global map against the one-process map |",
             "|---|---|---|---|---|---|---|"]
    for name, wall, cpu, rss, tasks, result, _ in rows:
        lines.append(f"| {name} | {wall:.1f} | {cpu:.1f} | {args.scans / wall:.2f} | {rss} | "
                     f"{tasks} | {result} |")
    text = "\n".join(lines) + "\n"
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    open(args.out, "w").write(text)
    print(text)


if __name__ == "__main__":
    main()
