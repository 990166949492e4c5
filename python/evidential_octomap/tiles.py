"""The two tasks of the tiled batch (batch.py) and what the client needs to schedule them.

A chunk task maps consecutive scans into a map of its own, as batch.map_chunk does (unbounded
occupancy, the evidence it could not place kept in an `unobserved` map), and writes both maps as
tiles (LocalMap's tile files: one octree node at a fixed depth each) into its work directory.
A tile task merges one tile key over every chunk that wrote it, in time order, exactly as
batch.merge_in_order merges whole chunk maps: addEvidence and merge are voxel by voxel, and no
pruned block spans two tiles, so the merge of a tile is the merge of the maps restricted to it.
A task thus holds one chunk's map, or a few tiles (the map and unplaced evidence merged so far,
the next chunk's two and what it could not place), never the whole map.

A scan changes only voxels within its reach of the sensor (LocalMap.reach), so a tile can get
evidence only from chunks whose sensor passed within that reach of it: once those chunks are
done, the tile is merged while later chunks are still mapping.
"""
from __future__ import annotations

import os
import shutil
import time
from dataclasses import dataclass
from typing import Iterable, Optional, Sequence

import numpy as np

from ._core import ClassTable, Dataset, EvidentialOcTree, LocalMap
from ._core import tile_file_name, write_tiles

Tile = tuple  # (x, y, z): key >> (16 - tile depth) per axis
KEY_OFFSET = 2 ** 15  # OctoMap's key of coordinate 0


@dataclass(frozen=True)
class ChunkTiles:
    """What a chunk task wrote: the tiles of its map and of its unplaced evidence."""

    index: int
    scans: int
    tiles: frozenset
    unobserved: frozenset
    evidence_log_sum: float
    evidence_points: int
    seconds: float = 0.0  # the task's wall time


def chunk_directory(work: str, index: int) -> str:
    return os.path.join(work, f"chunk_{index:06d}")


def tile_edge(resolution: float, tile_depth: int) -> float:
    return resolution * 2 ** (16 - tile_depth)


def reach_box(origins: np.ndarray, reach: float, resolution: float,
              tile_depth: int) -> Optional[tuple]:
    """The tiles (lowest, highest index per axis) within `reach` of any origin; None when the
    reach is unlimited (every tile)."""
    if reach < 0:
        return None
    edge = tile_edge(resolution, tile_depth)
    lo = np.floor((origins.min(axis=0) - reach + KEY_OFFSET * resolution) / edge).astype(int)
    hi = np.floor((origins.max(axis=0) + reach + KEY_OFFSET * resolution) / edge).astype(int)
    return tuple(np.clip(lo, 0, 2 ** tile_depth - 1)), tuple(np.clip(hi, 0, 2 ** tile_depth - 1))


def in_box(tile: Tile, box: Optional[tuple]) -> bool:
    return box is None or all(box[0][i] <= tile[i] <= box[1][i] for i in range(3))


def map_chunk_to_tiles(job, index: int, start: int, stop: int, work: str,
                       tile_depth: int) -> ChunkTiles:
    """Maps scans [start, stop) and writes the map's and the unplaced evidence's tiles under
    chunk_directory(work, index) (runs on a worker; a rerun writes the same files)."""
    from .batch import map_chunk, set_unbounded

    began = time.perf_counter()
    chunk = map_chunk(job, start, stop)
    set_unbounded(chunk.tree, False)  # the .ot format needs bounds; the values stay unclamped
    directory = chunk_directory(work, index)
    tiles, log_sum, points = write_tiles(chunk.tree, tile_depth, os.path.join(directory, "map"))
    unobserved, _, _ = write_tiles(chunk.unobserved, tile_depth,
                                   os.path.join(directory, "unobserved"))
    return ChunkTiles(index, stop - start, frozenset(tiles), frozenset(unobserved), log_sum, points,
                      time.perf_counter() - began)


def empty_like_job(job, classes: ClassTable) -> EvidentialOcTree:
    return EvidentialOcTree(job.resolution, classes, job.semantic_config())


def _read(path: str, job, classes: ClassTable) -> EvidentialOcTree:
    return EvidentialOcTree.load(path) if os.path.exists(path) else empty_like_job(job, classes)


def merge_tile(job, tile: Tile, tile_depth: int, chunks: Sequence[int], work: str,
               out: str) -> int:
    """Merges tile `tile` of chunks (in time order) into out/tile_...ot; returns its leaves
    (0: the chunks only held unplaced evidence there, no file). Deletes the chunk files once the
    tile is written; a rerun after that finds the tile and does nothing."""
    from .batch import fuse_in_order

    name = tile_file_name(tile_depth, tile)
    target = os.path.join(out, name)
    if os.path.exists(target):
        return EvidentialOcTree.load(target).num_leaves
    classes = ClassTable.load(job.classes)
    merged = unplaced = None
    for index in sorted(chunks):
        directory = chunk_directory(work, index)
        tree = _read(os.path.join(directory, "map", name), job, classes)
        unobserved = _read(os.path.join(directory, "unobserved", name), job, classes)
        if merged is None:
            merged, unplaced = tree, unobserved
            continue
        fuse_in_order(merged, unplaced, tree, unobserved, unclamped=True)
    leaves = merged.num_leaves if merged is not None else 0
    if leaves:
        merged.clamp_occupancy()  # once, at the end: occupancy does not depend on the chunks
        merged.save(target)
    remove_chunk_tiles(work, chunks, name)
    return leaves


def remove_chunk_tiles(work: str, chunks: Iterable[int], name: str) -> None:
    for index in chunks:
        for kind in ("map", "unobserved"):
            try:
                os.remove(os.path.join(chunk_directory(work, index), kind, name))
            except FileNotFoundError:
                pass


def scan_origins(job, start: int, stop: int) -> np.ndarray:
    dataset = Dataset.open(job.data, ClassTable.load(job.classes))
    return np.array([dataset.pose(i)[:3, 3] for i in range(start, stop)])


def scan_reach(job) -> float:
    classes = ClassTable.load(job.classes)
    return LocalMap.reach(empty_like_job(job, classes))


def remove_work(work: str) -> None:
    shutil.rmtree(work, ignore_errors=True)

