"""Merged vs sequential map on the bundled scans: the equality figures of docs/python.md.

    python python/tools/merge_equality.py 5 1      # chunk sizes to try

For each chunk size: the plain merge, the in-order merge (batch.merge_in_order), and the
in-order merge of unclamped chunk maps clamped at the end, each against the sequential map
(OctoMap clamping after every scan) and the sequential map clamped only at the end.
"""
import dataclasses
import sys
from pathlib import Path

import numpy as np

import evidential_octomap as eo
from evidential_octomap import batch

REPO = Path(__file__).resolve().parents[2]
SCANS = 10


def merged(job, chunk, in_order):
    chunks = [batch.map_chunk(job, s, e) for s, e in batch.chunk_ranges(SCANS, chunk)]

    def plain(earlier, later):
        earlier.tree.merge(later.tree)
        return earlier

    def in_order_merge(earlier, later):
        return batch.merge_in_order(earlier, later, job.unclamped)

    # A merge tree over neighbouring chunks (any such tree gives the same map).
    result = batch.reduce_in_pairs(chunks, in_order_merge if in_order else plain)
    if job.unclamped:
        result.tree.clamp_occupancy()
    return result.tree


def compare(name, reference, tree, points):
    a, b = reference.query(points), tree.query(points)
    ref, got = reference.leaves(), tree.query(reference.leaves().centers)
    same_leaves = tree.num_leaves == reference.num_leaves
    occupancy = (f"{(np.abs(ref.occupancy - tree.leaves().occupancy) > 1e-6).sum():,}"
                 if same_leaves else "-")
    print(f"| {name} | {(a.labels != b.labels).sum():,} | {np.abs(a.belief - b.belief).max():.1e} | "
          f"{tree.num_leaves:,} | {(ref.labels != got.labels).sum():,} | {occupancy} | "
          f"{(got.occupied != (ref.occupancy > 0.5)).sum():,} |")


def main():
    classes = str(REPO / "config" / "classes_semantickitti.yaml")
    job = batch.MappingJob(data=str(REPO / "data" / "semantickitti_08_first10"), classes=classes)
    unclamped = dataclasses.replace(job, unclamped=True)
    dataset = eo.Dataset.open(job.data, eo.ClassTable.load(classes))
    points = np.concatenate([dataset.load(i).points_world() for i in range(SCANS)])
    sequential = batch.map_chunk(job, 0, SCANS).tree
    end_clamped = batch.map_chunk(unclamped, 0, SCANS).tree
    end_clamped.clamp_occupancy()
    print(f"{len(points):,} query points; sequential map {sequential.num_leaves:,} leaves")
    print("| chunks, merge (reference) | labels differ | max belief diff | leaves | leaf labels "
          "differ | leaf log-odds differ | leaf occupied state differs |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for chunk in [int(k) for k in sys.argv[1:]] or [5]:
        n = -(-SCANS // chunk)
        compare(f"{n} x {chunk}, plain (sequential)", sequential, merged(job, chunk, False), points)
        compare(f"{n} x {chunk}, in order (sequential)", sequential, merged(job, chunk, True), points)
        in_order_unclamped = merged(unclamped, chunk, True)
        compare(f"{n} x {chunk}, in order, unclamped (sequential)", sequential, in_order_unclamped,
                points)
        compare(f"{n} x {chunk}, in order, unclamped (sequential clamped at the end)", end_clamped,
                in_order_unclamped, points)


if __name__ == "__main__":
    main()
