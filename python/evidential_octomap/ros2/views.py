"""The map's views as arrays, without ROS: the occupied leaves in a height band, their colours
(the Foxglove view's: class colours, P(label wrong) and conflict on one ramp), the ROS 1 node's
semantic_cloud columns, and the leaves grouped by size (one CUBE_LIST marker per size)."""
from typing import Dict, List, Tuple

import numpy as np

from ..foxglove_view import voxel_colors

VIEWS = ("class", "uncertainty", "conflict")


def occupied_leaves(tree, min_z: float = -np.inf, max_z: float = np.inf):
    """The occupied leaves whose centre lies in [min_z, max_z], as a Leaves-like object."""
    return in_band(tree.leaves(occupied_only=True), min_z, max_z)


def in_band(leaves, min_z: float = -np.inf, max_z: float = np.inf):
    keep = (leaves.centers[:, 2] >= min_z) & (leaves.centers[:, 2] <= max_z)
    return _Subset(leaves, keep) if not keep.all() else leaves


class _Subset:
    def __init__(self, leaves, keep):
        for name in ("centers", "sizes", "occupancy", "labels", "uncertainty", "conflict",
                     "error_probability", "belief"):
            setattr(self, name, getattr(leaves, name)[keep])


def packed_rgb(rgb01: np.ndarray) -> np.ndarray:
    """(N,) float32 whose bits are 0x00RRGGBB (PCL's and rviz's `rgb` field) of colours in
    [0, 1]."""
    c = np.clip(np.round(np.asarray(rgb01)[:, :3] * 255), 0, 255).astype(np.uint32)
    return ((c[:, 0] << 16) | (c[:, 1] << 8) | c[:, 2]).view(np.float32)


def cloud_columns(leaves, classes) -> Dict[str, np.ndarray]:
    """The ROS 1 node's semantic_cloud: voxel centres, label (-1 none), u, rgb (class colour),
    conflict and error_probability."""
    c = np.asarray(leaves.centers, dtype=np.float32)
    return {"x": c[:, 0], "y": c[:, 1], "z": c[:, 2],
            "label": np.asarray(leaves.labels, dtype=np.int32),
            "uncertainty": np.asarray(leaves.uncertainty, dtype=np.float32),
            "rgb": packed_rgb(voxel_colors(leaves, classes, "class")),
            "conflict": np.asarray(leaves.conflict, dtype=np.float32),
            "error_probability": np.asarray(leaves.error_probability, dtype=np.float32)}


def colours(leaves, classes, view: str, levels: int = 64) -> Tuple[np.ndarray, np.ndarray]:
    """(palette (K, 4), index (M,)): each leaf's colour as an index into a small palette (class
    colours, or the ramp in `levels` steps), so a marker reuses K colour messages."""
    rgba = voxel_colors(leaves, classes, view)
    if view != "class":
        rgba = np.round(rgba * (levels - 1)) / (levels - 1)
    palette, index = np.unique(rgba, axis=0, return_inverse=True)
    return palette, index.reshape(-1)


def by_size(leaves) -> List[Tuple[float, np.ndarray]]:
    """(edge length, leaf indices) per leaf size, smallest first."""
    sizes = np.asarray(leaves.sizes)
    return [(float(s), np.flatnonzero(sizes == s)) for s in np.unique(sizes)]
