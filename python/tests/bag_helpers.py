"""Helpers of the bag tests and of python/tools/bag_equality.py: a dataset copy whose poses TF
carries exactly, and leaf-by-leaf comparison of two maps."""
from pathlib import Path

import numpy as np

import evidential_octomap as eo
from evidential_octomap.tf_buffer import matrix, quaternion


def tf_exact_dataset(src: Path, dst: Path, classes, scans: int) -> Path:
    """The first scans of `src` with poses a TF message carries exactly.

    poses.txt's 3 x 4 matrices (12 decimals) are not exactly orthonormal, and TF carries a
    rotation as a quaternion, which differs from them by ~1e-9; that moves a few points across
    voxel borders. This copy stores the poses as TF rebuilds them (velodyne = camera frame,
    Tr = identity), so a bag and the directory describe the same scans bit for bit.
    """
    dataset = eo.Dataset.open(str(src), classes)
    for sub in ("velodyne", "labels", "predictions"):
        (dst / sub).mkdir(parents=True)
        for stem in dataset.stems[:scans]:
            ext = ".bin" if sub == "velodyne" else ".label"
            (dst / sub / (stem + ext)).symlink_to(src / sub / (stem + ext))
    lines = []
    for i in range(scans):
        T = dataset.pose(i)
        T = matrix(T[:3, 3], quaternion(T[:3, :3]))
        lines.append(" ".join(f"{v:.17g}" for v in T[:3, :4].ravel()))
    (dst / "poses.txt").write_text("\n".join(lines) + "\n")
    (dst / "calib.txt").write_text("Tr: 1 0 0 0 0 1 0 0 0 0 1 0\n")
    return dst


def compare_leaves(a, b) -> dict:
    """Leaves matched by centre and size: counts, labels that differ, largest payload gaps."""
    if (a.centers.shape == b.centers.shape and np.array_equal(a.centers, b.centers)
            and np.array_equal(a.sizes, b.sizes)):  # same leaves in the same order: no matching
        n = len(a.sizes)
        return {"leaves": (n, n), "common": n,
                "labels_differ": int((a.labels != b.labels).sum()),
                "belief": float(np.abs(a.belief - b.belief).max()),
                "uncertainty": float(np.abs(a.uncertainty - b.uncertainty).max()),
                "occupancy": float(np.abs(a.occupancy - b.occupancy).max())}

    def keyed(leaves):
        key = np.round(np.column_stack([leaves.centers, leaves.sizes]) * 1000).astype(np.int64)
        order = np.lexsort(key.T[::-1])
        return np.ascontiguousarray(key[order]).view([("", np.int64)] * 4).ravel(), order
    ka, oa = keyed(a)
    kb, ob = keyed(b)
    _, ia, ib = np.intersect1d(ka, kb, assume_unique=True, return_indices=True)
    ia, ib = oa[ia], ob[ib]
    return {"leaves": (len(ka), len(kb)), "common": len(ia),
            "labels_differ": int((a.labels[ia] != b.labels[ib]).sum()),
            "belief": float(np.abs(a.belief[ia] - b.belief[ib]).max()),
            "uncertainty": float(np.abs(a.uncertainty[ia] - b.uncertainty[ib]).max()),
            "occupancy": float(np.abs(a.occupancy[ia] - b.occupancy[ib]).max())}


def assert_same_map(figures):
    (n_a, n_b), common = figures["leaves"], figures["common"]
    assert n_a == n_b == common, figures
    assert figures["labels_differ"] == 0, figures
    assert figures["belief"] <= 1e-5 and figures["uncertainty"] <= 1e-5, figures
    assert figures["occupancy"] <= 1e-6, figures
