"""octomap_server's projected_map of a map, without ROS: a cell is occupied (100) if a leaf
over it whose centre lies in [min_z, max_z] is occupied, free (0) if such leaves are all free,
else unknown (-1); the grid spans the leaves' x-y extent at leaf resolution. The core's rule
(evidential_octomap/projected_grid.h), the ROS 1 node's projected_map."""
from dataclasses import dataclass

import numpy as np


@dataclass
class Grid:
    data: np.ndarray      # (height, width) int8, row-major from the origin (row = y)
    origin: tuple         # (x, y) of the grid's corner [m]
    resolution: float


def project(tree, min_z: float = -np.inf, max_z: float = np.inf) -> Grid:
    data, origin, resolution = tree.projected_map(min_z, max_z)
    return Grid(data, origin, resolution)
