"""Merged (in-order or plain, chunks of K scans) vs sequential map on the bundled scans: the
equality figures of docs/python.md. Usage: python python/tools/merge_equality.py K [K ...]"""
import sys
from pathlib import Path

import numpy as np

import evidential_octomap as eo
from evidential_octomap import batch
REPO = Path(__file__).resolve().parents[2]
job = batch.MappingJob(data=f"{REPO}/data/semantickitti_08_first10", classes=f"{REPO}/config/classes_semantickitti.yaml")
n = 10
seq = batch.map_chunk(job, 0, n).tree
ds = eo.Dataset.open(job.data, eo.ClassTable.load(job.classes))
points = np.concatenate([ds.load(i).points_world() for i in range(n)])
a = seq.query(points)
L = seq.leaves()
for k in [int(x) for x in sys.argv[1:]]:
    chunks = [batch.map_chunk(job, s, e) for s, e in batch.chunk_ranges(n, k)]
    plain = chunks[0].tree.copy()
    for c in chunks[1:]: plain.merge(c.tree)
    merged = chunks[0]
    for c in chunks[1:]: merged = batch.merge_in_order(merged, c)
    for name, t in (("plain merge", plain), ("in-order merge", merged.tree)):
        b = t.query(points); lb = t.query(L.centers)
        print(f"chunks of {k} ({len(chunks)} chunks), {name}: query labels differ {(a.labels != b.labels).sum()} of {len(points)}, "
              f"max |belief diff| {np.abs(a.belief - b.belief).max():.2e}, known differ {(a.known != b.known).sum()}, "
              f"occupied differ {(a.occupied != b.occupied).sum()} queries; leaves {t.num_leaves} vs {seq.num_leaves}, "
              f"leaf labels differ {(L.labels != lb.labels).sum()}, leaf occupancy differs {(np.abs(L.occupancy - t.leaves().occupancy) > 0).sum() if t.num_leaves == seq.num_leaves else 'n/a'}, "
              f"leaf occupied status differs {(lb.occupied != (L.occupancy > 0.5)).sum()} of {len(L.labels)}")
