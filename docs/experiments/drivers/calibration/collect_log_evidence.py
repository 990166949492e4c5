#!/usr/bin/python3
"""Reads back the fused log-evidence L of every GT query point from the maps select_cap.sh built
(dempster, read-out cap 80, so L below 80 comes back exactly and above it in proportion), with
each map's own adaptive-cap statistic m. Writes <out>/L_<name>.npz per dataset.

    python docs/experiments/drivers/calibration/collect_log_evidence.py OUT_DIR    (the venv's python)
"""
import os
import sys

import numpy as np

import evidential_octomap as eo

PROTOCOLS = ("reconstruction", "held-out")


def query_points(classes, dataset, scan_ids):
    points, gt = [], []
    for i in scan_ids:
        scan = dataset.load(i)
        keep = (scan.gt != classes.ignore_class) & (scan.gt >= 0)
        points.append(scan.points_world()[keep])
        gt.append(scan.gt[keep])
    return np.concatenate(points), np.concatenate(gt)


def log_evidence(tree, points):
    """L^c = log1p(b^c / u) of each query's voxel (0 where the voxel holds no evidence)."""
    q = tree.query(points)
    b, u = q.belief.astype(np.float64), q.uncertainty.astype(np.float64)
    L = np.log1p(b / np.maximum(u, 1e-300)[:, None])
    L[q.labels < 0] = 0.0
    return L, q.labels >= 0


def collect(out, name, data, classes_path):
    target = os.path.join(out, "L_%s.npz" % name)
    if os.path.exists(target):
        return
    classes = eo.ClassTable.load(classes_path)
    dataset = eo.Dataset.open(data, classes)
    n = len(dataset)
    arrays = {"C": classes.num_classes}
    for protocol, scan_ids in zip(PROTOCOLS, (range(n), range(n // 2, n))):
        tree = eo.EvidentialOcTree.load(os.path.join(out, "maps", "%s_%s" % (name, protocol),
                                                     "map.ot"))
        points, gt = query_points(classes, dataset, scan_ids)
        L, labelled = log_evidence(tree, points)
        arrays.update({protocol + "_L": L.astype(np.float32), protocol + "_labelled": labelled,
                       protocol + "_gt": gt, protocol + "_m": tree.mean_point_log_evidence})
    np.savez_compressed(target, **arrays)
    print("%s: m = %.3f (reconstruction)" % (name, arrays["reconstruction_m"]), flush=True)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    with open(os.path.join(out, "manifest.tsv")) as f:
        for line in f:
            name, data, classes_path = line.split()
            collect(out, name, data, classes_path)


if __name__ == "__main__":
    main()
