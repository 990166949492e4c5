"""Batch mapping of a long sequence on Dask, by time and by space: chunks of scans are mapped on
workers and written as tiles, each tile is merged over the chunks that wrote it, and the result
is a tiled map (a directory: tiled_map.yaml and one .ot per tile; TiledMap opens it) equal to
the sequentially built map, plus on request one global .ot streamed tile by tile.

    python -m evidential_octomap.batch --data data/semantickitti_08_first10 \\
        --classes config/classes_semantickitti.yaml --out out/batch/tiles --chunk-size 2 \\
        --global-map out/batch/map.ot --set max_range=50

Local by default (a LocalCluster); ``--scheduler tcp://host:8786`` runs the same job on a Dask
cluster whose workers see --data and --out at the same paths (a shared directory).

Why the merge is exact: each chunk map keeps the evidence it could not place (its voxels were not
observed yet inside the chunk); merging an earlier and a later chunk first hands the later
chunk's unplaced evidence to the voxels the earlier chunk observed (EvidentialOcTree.add_evidence),
then fuses the maps (Dempster's rule in evidence space is commutative and associative). Both
steps work voxel by voxel, so they split into tiles (tiles.py): no task ever holds more than one
chunk's map or three tiles. Occupancy log-odds are summed unclamped and clamped once per tile at
the end, so the result does not depend on the chunking or the number of workers; it equals the
sequential map clamped once at the end (OctoMap clamps after every scan, which no merge can
reproduce), both with clearing off (MappingJob.semantic_config).
"""
from __future__ import annotations

import argparse
import dataclasses
import logging
import os
import sys
import time
from statistics import fmean as mean
from dataclasses import dataclass, field
from typing import Callable, Optional, Sequence

from ._core import ClassTable, Dataset, EvidentialOcTree, SemanticConfig, derive_evidence
from ._core import EVIDENCE_MAGNITUDE, TiledMap, evidence_is_derived, tile_depth_for_edge
from ._core import write_tiled_map_manifest
from . import tiles

FLT_MAX = 3.4028234663852886e38  # largest float: "unbounded" log-odds that still save as .ot
CLEARINGS = ("clearing_observations", "movable_clearing_observations")


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
        """The job's settings; clearing is off (a chunk's clearings cannot reach the evidence
        that another chunk holds, so no merge could equal the sequential map with it)."""
        for name in CLEARINGS:
            if self.config.get(name, 0):
                raise ValueError(f"batch mapping cannot apply {name}: a chunk's clearings "
                                 "cannot reach another chunk's evidence; map sequentially")
        return SemanticConfig(**{**{name: 0 for name in CLEARINGS}, **self.config})


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
    fuse_in_order(earlier.tree, earlier.unobserved, later.tree, later.unobserved, unclamped)
    return ChunkMap(earlier.first_scan, later.last_scan, earlier.tree, earlier.unobserved)


def fuse_in_order(tree: EvidentialOcTree, unobserved: EvidentialOcTree,
                  later: EvidentialOcTree, later_unobserved: EvidentialOcTree,
                  unclamped: bool) -> None:
    """tree and unobserved become the map and the unplaced evidence of both (in place)."""
    rest = EvidentialOcTree(tree.resolution, tree.class_names, tree.config)
    rest.ground_classes = tree.ground_classes
    rest.movable_classes = tree.movable_classes
    tree.add_evidence(later_unobserved, rest)  # before the later chunk's observations
    set_unbounded(tree, unclamped)
    tree.merge(later)
    set_unbounded(tree, False)
    unobserved.merge(rest)


def reduce_in_pairs(items: list, combine: Callable):
    """Combines neighbours level by level, ((0 1)(2 3))(4 ..): a merge tree whose shape depends on
    len(items) only. `combine` may return futures (the levels then run on the workers)."""
    while len(items) > 1:
        paired = [combine(items[i], items[i + 1]) for i in range(0, len(items) - 1, 2)]
        items = paired + ([items[-1]] if len(items) % 2 else [])
    return items[0]


class Progress:
    """One status line on stderr: scans mapped and tiles merged, with elapsed time."""

    def __init__(self, scans: int, enabled: bool):
        self.scans, self.mapped, self.tiles, self.merged = scans, 0, 0, 0
        self.enabled = enabled
        self.start = time.monotonic()

    def update(self, mapped: int = 0, tiles: int = 0, merged: int = 0) -> None:
        self.mapped += mapped
        self.tiles += tiles
        self.merged += merged
        if not self.enabled:
            return
        bar = "#" * (30 * self.mapped // self.scans)
        sys.stderr.write(f"\r[{bar:<30}] {self.mapped}/{self.scans} scans mapped, "
                         f"{self.merged}/{self.tiles} tiles merged, "
                         f"{time.monotonic() - self.start:.1f} s")
        sys.stderr.flush()

    def close(self) -> None:
        if self.enabled:
            sys.stderr.write("\n")


@dataclass
class TiledResult:
    """A finished batch: the tiled map's directory and what it took."""

    directory: str
    tiles: int
    chunks: int
    scans: int
    chunk_seconds: list  # each chunk task's wall time
    merge_seconds: list  # each tile task's wall time


class TileSchedule:
    """Which tiles may be merged: a tile is ready once every chunk whose sensor came within a
    scan's reach of it is mapped (tiles.reach_box); the chunks that wrote it, in time order,
    are its inputs."""

    def __init__(self, boxes: list):
        self.boxes = boxes
        self.waiting: dict = {}  # tile -> chunks not mapped yet that may write it
        self.inputs: dict = {}  # tile -> chunks that wrote it
        self.done: set = set()

    def mapped(self, result: tiles.ChunkTiles) -> list:
        """Records a mapped chunk; returns the tiles now ready, each with its input chunks."""
        self.done.add(result.index)
        for tile in result.tiles | result.unobserved:
            if not tiles.in_box(tile, self.boxes[result.index]):
                raise RuntimeError(f"chunk {result.index} wrote tile {tile} beyond the reach of "
                                   "its scans (a pose that is not the scan's origin?)")
            if tile not in self.inputs:
                self.inputs[tile] = []
                self.waiting[tile] = {c for c, box in enumerate(self.boxes)
                                      if c not in self.done and tiles.in_box(tile, box)}
            self.inputs[tile].append(result.index)
        ready = []
        for tile, chunks in list(self.waiting.items()):
            chunks.discard(result.index)
            if not chunks:
                del self.waiting[tile]
                ready.append((tile, sorted(self.inputs.pop(tile))))
        return ready


def chunk_plan(job: MappingJob, then: Sequence[str], scans: Optional[int],
               chunk_size: int) -> list:
    """(job, start, stop) of every chunk: job.data's first `scans` scans (all when None), then
    those of each sequence in `then`, in that order."""
    plan = []
    for data in [job.data, *then]:
        part = dataclasses.replace(job, data=data)
        available = len(Dataset.open(data, ClassTable.load(job.classes)))
        count = available if scans is None else min(scans, available)
        if count < 1:
            raise ValueError(f"no scans to map in {data}")
        plan += [(part, a, b) for a, b in chunk_ranges(count, chunk_size)]
    return plan


def map_sequence(client, job: MappingJob, out: str, scans: Optional[int] = None,
                 chunk_size: int = 10, tile_edge: float = 25.6, retries: int = 2,
                 progress: bool = True, chunk_fn: Callable = None,
                 then: Sequence[str] = ()) -> TiledResult:
    """Maps scans 0..scans-1 (all when None) of job.data on a Dask client into the tiled map
    `out` (a new or empty directory, on a filesystem every worker sees). `then`: further
    sequences in the same world frame (a fleet's logs of one area), mapped as if one robot had
    driven them after job.data, one after the other.

    Each task is retried `retries` times when it raises; a lost worker's tasks are rescheduled by
    Dask and rewrite the same files. The result does not depend on the number of workers."""
    from distributed import as_completed

    if os.path.isdir(out) and os.listdir(out):
        raise ValueError(f"{out} is not empty: give a new directory for the tiled map")
    job = dataclasses.replace(job, unclamped=True)  # clamped once per tile, at the end
    plan = chunk_plan(job, then, scans, chunk_size)
    count = sum(b - a for _, a, b in plan)
    tile_depth = tile_depth_for_edge(job.resolution, tile_edge)
    work = os.path.join(out, ".work")
    os.makedirs(work, exist_ok=True)
    reach = tiles.scan_reach(job)
    boxes = [tiles.reach_box(tiles.scan_origins(part, a, b), reach, job.resolution, tile_depth)
             for part, a, b in plan]
    schedule = TileSchedule(boxes)
    bar = Progress(count, progress)
    chunk_fn = chunk_fn or tiles.map_chunk_to_tiles
    pending = as_completed([client.submit(chunk_fn, part, i, a, b, work, tile_depth,
                                          retries=retries, pure=False, priority=-i)
                            for i, (part, a, b) in enumerate(plan)])
    written, log_sum, points = [], 0.0, 0
    statistics, chunk_seconds, merge_seconds = {}, [], []
    for future in pending:
        result = future.result()
        future.release()  # a finished task is never rerun for a lost worker
        if isinstance(result, tiles.ChunkTiles):
            statistics[result.index] = (result.evidence_log_sum, result.evidence_points)
            chunk_seconds.append(result.seconds)
            ready = schedule.mapped(result)
            bar.update(mapped=result.scans, tiles=len(ready))
            for tile, chunks in ready:
                pending.add(client.submit(merge_tile_task, job, tile, tile_depth, chunks, work,
                                          out, retries=retries, pure=False, priority=1))
        else:
            tile, leaves, seconds = result
            merge_seconds.append(seconds)
            if leaves:
                written.append(tile)
            bar.update(merged=1)
    bar.close()
    for index in sorted(statistics):  # summed in time order: the same for any worker count
        log_sum += statistics[index][0]
        points += statistics[index][1]
    tiles.remove_work(work)
    reference = tiles.empty_like_job(job, ClassTable.load(job.classes))
    write_tiled_map_manifest(out, job.resolution, tile_depth, reference.class_names,
                             reference.rule, log_sum, points, sorted(written))
    return TiledResult(out, len(written), len(plan), count, chunk_seconds, merge_seconds)


def merge_tile_task(job, tile, tile_depth, chunks, work, out):
    began = time.perf_counter()
    leaves = tiles.merge_tile(job, tile, tile_depth, chunks, work, out)
    return tile, leaves, time.perf_counter() - began


def local_client(workers: Optional[int], threads: Optional[int] = None):
    """A LocalCluster of single-threaded worker processes (one per core by default); each
    worker's OpenMP threads get `threads` cores (default: an equal share)."""
    from distributed import Client, LocalCluster

    cores = os.cpu_count() or 1
    workers = workers or cores
    threads = threads or max(1, cores // workers)
    # Task errors reach the caller as exceptions; the workers' own logs would only add shutdown
    # noise (heartbeats racing the scheduler's close).
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           dashboard_address=":0", silence_logs=logging.CRITICAL,
                           env={"OMP_NUM_THREADS": str(threads)})
    return Client(cluster)


def parse_arguments(argv: Optional[Sequence[str]]) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        prog="python -m evidential_octomap.batch",
        description="Map a SemanticKITTI-layout sequence in chunks on Dask workers into a tiled "
                    "map equal to the sequentially built one (and, on request, one .ot).")
    p.add_argument("--data", required=True, action="append",
                   help="dataset directory (velodyne/, poses.txt, ...); repeated: sequences of "
                        "one area in one world frame (a fleet's), mapped as if one robot had "
                        "driven them one after the other")
    p.add_argument("--classes", required=True, help="class table YAML (config/classes_*.yaml)")
    p.add_argument("--out", required=True,
                   help="the tiled map: a new directory (shared with the workers)")
    p.add_argument("--global-map", default=None, metavar="MAP.ot",
                   help="also write the whole map as one .ot, streamed tile by tile")
    p.add_argument("--scans", type=int, default=None,
                   help="map only the first N scans (of each sequence)")
    p.add_argument("--chunk-size", type=int, default=10, help="scans per chunk (default 10)")
    p.add_argument("--tile-edge", type=float, default=25.6,
                   help="largest tile edge [m] (default 25.6: 128 voxels at 0.2 m)")
    p.add_argument("--scheduler", default=None,
                   help="address of a Dask scheduler (tcp://host:8786); default: a local cluster")
    p.add_argument("--workers", type=int, default=None,
                   help="local worker processes (default: one per core)")
    p.add_argument("--threads", type=int, default=None,
                   help="OpenMP threads of each local worker (default: cores / workers)")
    p.add_argument("--retries", type=int, default=2, help="retries of a failing task (default 2)")
    p.add_argument("--resolution", type=float, default=0.2, help="voxel size [m] (default 0.2)")
    p.add_argument("--evidence", default="onehot",
                   help="'file' (evidence/ or alpha/ files), or derived from hard labels: "
                        "'onehot' (default) or 'knn-vote'")
    p.add_argument("-E", "--evidence-magnitude", type=float, default=EVIDENCE_MAGNITUDE,
                   help="E of derived evidence (default 20)")
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
    job = MappingJob(data=os.path.abspath(args.data[0]), classes=os.path.abspath(args.classes),
                     resolution=args.resolution, config=config_overrides(args.set),
                     evidence=args.evidence, magnitude=args.evidence_magnitude)
    from distributed import Client

    start = time.monotonic()
    client = Client(args.scheduler) if args.scheduler else local_client(args.workers, args.threads)
    try:
        workers = len(client.scheduler_info()["workers"])
        derived = " (DERIVED from hard labels)" if evidence_is_derived(job.evidence) else ""
        print(f"mapping {', '.join(args.data)} on {workers} workers, {args.chunk_size} scans per chunk, "
              f"evidence {job.evidence}{derived}", file=sys.stderr)
        result = map_sequence(client, job, os.path.abspath(args.out), args.scans,
                              args.chunk_size, args.tile_edge, args.retries, not args.quiet,
                              then=[os.path.abspath(d) for d in args.data[1:]])
    finally:
        cluster = getattr(client, "cluster", None)
        client.close()
        if cluster is not None and not args.scheduler:
            cluster.close()
    print(f"wrote {args.out}: {result.tiles} tiles from {result.chunks} chunks of "
          f"{result.scans} scans ({time.monotonic() - start:.1f} s)")
    print(f"task wall times: chunk {mean(result.chunk_seconds or [0]):.2f} s x {result.chunks}, tile "
          f"merge {mean(result.merge_seconds or [0]):.3f} s x {len(result.merge_seconds)}")
    if args.global_map:
        os.makedirs(os.path.dirname(os.path.abspath(args.global_map)), exist_ok=True)
        TiledMap(result.directory).write_global_map(args.global_map)
        print(f"wrote {args.global_map} ({time.monotonic() - start:.1f} s)")
    return 0


if __name__ == "__main__":
    # Run the imported module's main, so workers unpickle its functions by reference.
    from evidential_octomap.batch import main as batch_main

    sys.exit(batch_main())
