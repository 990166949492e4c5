"""octomap_server's projected_map from the leaves, without ROS: a cell is occupied (100) if a
leaf over it whose centre lies in [min_z, max_z] is occupied, free (0) if such leaves are all
free, else unknown (-1); the grid spans the leaves' x-y extent at leaf resolution. The same rule
as the ROS 1 node's projectOccupancy (src/ros/projected_map.cpp), vectorised with numpy."""
from dataclasses import dataclass

import numpy as np


@dataclass
class Grid:
    data: np.ndarray      # (height, width) int8, row-major from the origin (row = y)
    origin: tuple         # (x, y) of the grid's corner [m]
    resolution: float


def project(tree, min_z: float = -np.inf, max_z: float = np.inf) -> Grid:
    return project_leaves(tree.leaves(opinions=False), tree.resolution, tree.occupancy_thres,
                          min_z, max_z)


def project_leaves(leaves, res: float, occupancy_thres: float, min_z: float = -np.inf,
                   max_z: float = np.inf) -> Grid:
    """The same from every leaf of a map (tree.leaves(opinions=False) is enough), e.g. copied
    out under a lock."""
    if len(leaves.sizes) == 0:
        return Grid(np.zeros((0, 0), dtype=np.int8), (0.0, 0.0), res)
    cells = np.rint(leaves.sizes / res).astype(np.int64)
    corner = np.rint((leaves.centers[:, :2] - leaves.sizes[:, None] / 2) / res).astype(np.int64)
    lo = corner.min(axis=0)
    hi = (corner + cells[:, None]).max(axis=0)
    width, height = hi - lo
    band = (leaves.centers[:, 2] >= min_z) & (leaves.centers[:, 2] <= max_z)
    occupied = leaves.occupancy > occupancy_thres
    data = np.full((height, width), -1, dtype=np.int8)
    covered = np.zeros((height, width), dtype=bool)
    hit = np.zeros((height, width), dtype=bool)
    for n in np.unique(cells[band]):
        pick = band & (cells == n)
        offsets = np.arange(n)
        ix = (corner[pick, 0] - lo[0])[:, None, None] + offsets[None, None, :]
        iy = (corner[pick, 1] - lo[1])[:, None, None] + offsets[None, :, None]
        ix, iy = np.broadcast_arrays(ix, iy)
        covered[iy, ix] = True
        occ = occupied[pick]
        hit[iy[occ], ix[occ]] = True
    data[covered] = 0
    data[hit] = 100
    return Grid(data, (float(lo[0] * res), float(lo[1] * res)), res)
