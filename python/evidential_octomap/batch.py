"""Batch mapping of a long sequence on Dask: chunks of scans are mapped on workers and the chunk
maps are merged in time order into one .ot that equals the sequentially built map.

    python -m evidential_octomap.batch --data data/semantickitti_08_first10 \\
        --classes config/classes_semantickitti.yaml --out out/batch/map.ot --chunk-size 2

Local by default (a LocalCluster with one single-threaded worker per core); ``--scheduler
tcp://host:8786`` runs the same job on a Dask cluster. Why the merge is exact: each chunk map keeps
the evidence it could not place (its voxels were not observed yet inside the chunk); merging an
earlier and a later chunk first hands the later chunk's unplaced evidence to the voxels the earlier
chunk observed (EvidentialOcTree.add_evidence), then fuses the maps (Dempster's rule in evidence
space is commutative and associative). The merge tree pairs neighbouring chunks, so its shape
depends on the number of chunks only, never on the number of workers.
"""
from __future__ import annotations

import argparse
import logging
import os
import sys
import time
from dataclasses import dataclass, field
from typing import Callable, Optional, Sequence

from ._core import ClassTable, Dataset, EvidentialOcTree, SemanticConfig, derive_evidence
from ._core import EVIDENCE_MAGNITUDE, evidence_is_derived

FLT_MAX = 3.4028234663852886e38  # largest float: "unbounded" log-odds that still save as .ot


@dataclass(frozen=True)
class MappingJob:
    """Everything a worker needs to map scans of one sequence (plain data, cheap to send)."""

    data: str
    classes: str
    resolution: float = 0.2
    config: dict = field(default_factory=dict)  # SemanticConfig fields by name
    evidence: str = "onehot"
    magnitude: float = EVIDENCE_MAGNITUDE
    # Chunk maps keep unbounded occupancy log-odds and the merged map is clamped once at the end,
    # so occupancy does not depend on the chunking (OctoMap clamps after every scan instead).
    unclamped: bool = False

    def semantic_config(self) -> SemanticConfig:
        return SemanticConfig(**self.config)


@dataclass
class ChunkMap:
    """A chunk's map and the evidence it could not place (voxels it had not observed yet)."""

    first_scan: int
    last_scan: int
    tree: EvidentialOcTree
    unobserved: EvidentialOcTree


def chunk_ranges(num_scans: int, chunk_size: int) -> list[tuple[int, int]]:
    """[start, stop) of consecutive chunks (the last may be shorter)."""
    if chunk_size < 1:
        raise ValueError(f"chunk size must be >= 1, got {chunk_size}")
    return [(s, min(s + chunk_size, num_scans)) for s in range(0, num_scans, chunk_size)]


def map_chunk(job: MappingJob, start: int, stop: int) -> ChunkMap:
    """Maps scans [start, stop) into a new map (runs on a worker)."""
    classes = ClassTable.load(job.classes)
    dataset = Dataset.open(job.data, classes)
    config = job.semantic_config()
    tree = EvidentialOcTree(job.resolution, classes, config)
    unobserved = EvidentialOcTree(job.resolution, classes, config)
    set_unbounded(tree, job.unclamped)
    for i in range(start, stop):
        scan = dataset.load(i)
        evidence = derive_evidence(scan, classes.num_classes, job.evidence, job.magnitude)
        tree.insert_scan(scan.points_world(), evidence, origin=scan.origin, unobserved=unobserved)
    set_unbounded(tree, False)
    return ChunkMap(start, stop - 1, tree, unobserved)


def set_unbounded(tree: EvidentialOcTree, unbounded: bool) -> None:
    """Unbounded occupancy log-odds (while mapping or merging unclamped chunk maps), else
    OctoMap's default bounds, which a map must carry whenever it is stored or sent (the .ot
    format checks them; the log-odds themselves stay as they are)."""
    if unbounded:
        tree.set_clamping_thres_log(-FLT_MAX, FLT_MAX)
    else:
        defaults = EvidentialOcTree(tree.resolution)
        tree.set_clamping_thres_log(defaults.clamping_thres_min_log, defaults.clamping_thres_max_log)


def merge_in_order(earlier: ChunkMap, later: ChunkMap, unclamped: bool = False) -> ChunkMap:
    """The map of both chunks, as if their scans had been inserted one after the other
    (occupancy log-odds added without clamping when `unclamped`)."""
    if earlier.last_scan + 1 != later.first_scan:
        raise ValueError(f"chunks must be neighbours: scans ..{earlier.last_scan} and "
                         f"{later.first_scan}..")
    rest = EvidentialOcTree(earlier.tree.resolution, earlier.tree.class_names, earlier.tree.config)
    rest.ground_classes = earlier.tree.ground_classes
    earlier.tree.add_evidence(later.unobserved, rest)  # before the later chunk's observations
    set_unbounded(earlier.tree, unclamped)
    earlier.tree.merge(later.tree)
    set_unbounded(earlier.tree, False)
    earlier.unobserved.merge(rest)
    return ChunkMap(earlier.first_scan, later.last_scan, earlier.tree, earlier.unobserved)


def reduce_in_pairs(items: list, combine: Callable):
    """Combines neighbours level by level, ((0 1)(2 3))(4 ..): a merge tree whose shape depends on
    len(items) only. `combine` may return futures (the levels then run on the workers)."""
    while len(items) > 1:
        paired = [combine(items[i], items[i + 1]) for i in range(0, len(items) - 1, 2)]
        items = paired + ([items[-1]] if len(items) % 2 else [])
    return items[0]


class Progress:
    """One status line on stderr: chunks mapped and merges done, with elapsed time."""

    def __init__(self, chunks: int, enabled: bool):
        self.chunks, self.merges = chunks, max(chunks - 1, 0)
        self.mapped = self.merged = 0
        self.enabled = enabled
        self.start = time.monotonic()

    def update(self, mapped: int = 0, merged: int = 0) -> None:
        self.mapped += mapped
        self.merged += merged
        if not self.enabled:
            return
        total = self.chunks + self.merges
        done = self.mapped + self.merged
        bar = "#" * (30 * done // total) if total else ""
        sys.stderr.write(f"\r[{bar:<30}] {self.mapped}/{self.chunks} chunks mapped, "
                         f"{self.merged}/{self.merges} merged, {time.monotonic() - self.start:.1f} s")
        if done == total:
            sys.stderr.write("\n")
        sys.stderr.flush()


def map_sequence(client, job: MappingJob, scans: Optional[int] = None, chunk_size: int = 10,
                 retries: int = 2, progress: bool = True,
                 chunk_fn: Callable[[MappingJob, int, int], ChunkMap] = map_chunk) -> EvidentialOcTree:
    """Maps scans 0..scans-1 (all when None) of job.data on a Dask client; returns the merged map.

    Each task is retried `retries` times when it raises; a lost worker's tasks are rescheduled by
    Dask. The result does not depend on the number of workers."""
    from distributed import as_completed

    available = len(Dataset.open(job.data, ClassTable.load(job.classes)))
    count = available if scans is None else min(scans, available)
    if count < 1:
        raise ValueError(f"no scans to map in {job.data}")
    ranges = chunk_ranges(count, chunk_size)
    bar = Progress(len(ranges), progress)
    # Memory: a merge runs as soon as its two inputs exist (merges outrank chunks, deeper merges
    # first), and a map is released once the merge that consumed it is done (no future refers
    # to it any more), so a worker holds about one map per level of the merge tree instead of
    # every chunk map of the sequence.
    chunks = [client.submit(chunk_fn, job, start, stop, retries=retries, pure=False)
              for start, stop in ranges]
    depth = {f.key: 0 for f in chunks}
    merges, inputs = [], {}  # inputs: merge key -> the two futures it consumes

    def submit_merge(earlier, later):
        level = 1 + max(depth[earlier.key], depth[later.key])
        merges.append(client.submit(merge_in_order, earlier, later, job.unclamped,
                                    retries=retries, pure=False, priority=level))
        depth[merges[-1].key] = level
        inputs[merges[-1].key] = (earlier, later)
        return merges[-1]

    result = reduce_in_pairs(chunks, submit_merge)
    pending = as_completed(chunks + merges)
    chunks.clear()
    merges.clear()
    for future in pending:
        consumed = inputs.pop(future.key, None)  # dropped at the next step: its maps go
        bar.update(merged=int(consumed is not None), mapped=int(consumed is None))
    tree = result.result().tree
    if job.unclamped:
        tree.clamp_occupancy()  # once, at the end
    return tree


def local_client(workers: Optional[int]):
    """A LocalCluster of single-threaded worker processes (one per core by default); each
    worker's OpenMP threads get an equal share of the cores."""
    from distributed import Client, LocalCluster

    cores = os.cpu_count() or 1
    workers = workers or cores
    threads = str(max(1, cores // workers))
    # Task errors reach the caller as exceptions; the workers' own logs would only add shutdown
    # noise (heartbeats racing the scheduler's close).
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           dashboard_address=":0", silence_logs=logging.CRITICAL,
                           env={"OMP_NUM_THREADS": threads})
    return Client(cluster)


def parse_arguments(argv: Optional[Sequence[str]]) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        prog="python -m evidential_octomap.batch",
        description="Map a SemanticKITTI-layout sequence in chunks on Dask workers and merge the "
                    "chunk maps exactly into one .ot.")
    p.add_argument("--data", required=True, help="dataset directory (velodyne/, poses.txt, ...)")
    p.add_argument("--classes", required=True, help="class table YAML (config/classes_*.yaml)")
    p.add_argument("--out", required=True, help="merged map (.ot)")
    p.add_argument("--scans", type=int, default=None, help="map only the first N scans")
    p.add_argument("--chunk-size", type=int, default=10, help="scans per chunk (default 10)")
    p.add_argument("--scheduler", default=None,
                   help="address of a Dask scheduler (tcp://host:8786); default: a local cluster")
    p.add_argument("--workers", type=int, default=None,
                   help="local worker processes (default: one per core)")
    p.add_argument("--retries", type=int, default=2, help="retries of a failing task (default 2)")
    p.add_argument("--resolution", type=float, default=0.2, help="voxel size [m] (default 0.2)")
    p.add_argument("--evidence", default="onehot",
                   help="'file' (evidence/ or alpha/ files), or derived from hard labels: "
                        "'onehot' (default) or 'knn-vote'")
    p.add_argument("-E", "--evidence-magnitude", type=float, default=EVIDENCE_MAGNITUDE,
                   help="E of derived evidence (default 20)")
    p.add_argument("--unclamped-merge", action="store_true",
                   help="keep chunk maps' occupancy unclamped and clamp once after the merge: "
                        "occupancy then does not depend on the chunking")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="a SemanticConfig parameter, e.g. --set rule=sbki --set max_range=50")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    return p.parse_args(argv)


def config_overrides(settings: Sequence[str]) -> dict:
    """NAME=VALUE pairs typed like SemanticConfig's defaults."""
    defaults = SemanticConfig()
    overrides = {}
    for setting in settings:
        name, sep, text = setting.partition("=")
        if not sep or not hasattr(defaults, name):
            raise SystemExit(f"--set {setting}: expected NAME=VALUE with a SemanticConfig field")
        kind = type(getattr(defaults, name))
        overrides[name] = text.lower() in ("1", "true", "yes", "on") if kind is bool else kind(text)
    return overrides


def main(argv: Optional[Sequence[str]] = None) -> int:
    args = parse_arguments(argv)
    job = MappingJob(data=os.path.abspath(args.data), classes=os.path.abspath(args.classes),
                     resolution=args.resolution, config=config_overrides(args.set),
                     evidence=args.evidence, magnitude=args.evidence_magnitude,
                     unclamped=args.unclamped_merge)
    from distributed import Client

    start = time.monotonic()
    client = Client(args.scheduler) if args.scheduler else local_client(args.workers)
    try:
        workers = len(client.scheduler_info()["workers"])
        derived = " (DERIVED from hard labels)" if evidence_is_derived(job.evidence) else ""
        print(f"mapping {job.data} on {workers} workers, {args.chunk_size} scans per chunk, "
              f"evidence {job.evidence}{derived}", file=sys.stderr)
        tree = map_sequence(client, job, args.scans, args.chunk_size, args.retries,
                            not args.quiet)
    finally:
        cluster = getattr(client, "cluster", None)
        client.close()
        if cluster is not None and not args.scheduler:
            cluster.close()
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    tree.save(args.out)
    print(f"wrote {args.out}: {tree.num_leaves} leaves, {tree.num_semantic_nodes} semantic nodes "
          f"({time.monotonic() - start:.1f} s)")
    return 0


if __name__ == "__main__":
    # Run the imported module's main, so workers unpickle its functions by reference.
    from evidential_octomap.batch import main as batch_main

    sys.exit(batch_main())
