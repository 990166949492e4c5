"""The ROS 2 node's pieces that need no ROS: the projected map against a cell-by-cell walk of
the leaves, the packed colours of semantic_cloud, and the latest-only insert queue."""
import numpy as np
import pytest

import evidential_octomap as eo
from evidential_octomap.ros2 import projection, views
from evidential_octomap.ros2.latest_queue import LatestQueue
from conftest import wall


@pytest.fixture(scope="module")
def tree():
    t = eo.EvidentialOcTree(0.2, ["a", "b", "c"])
    for x in (4.0, 6.0):
        points, evidence = wall(x=x)
        t.insert_scan(points, evidence, origin=(0.0, 0.0, 0.5))
    return t


def walked(tree, min_z, max_z):
    """The rule, one leaf and one cell at a time: 100 under an occupied leaf of the band, else 0
    under a free one, else -1."""
    res, leaves = tree.resolution, tree.leaves()
    grid = projection.project(tree, min_z, max_z)
    out = np.full(grid.data.shape, -1, dtype=np.int8)
    for c, size, occ in zip(leaves.centers, leaves.sizes, leaves.occupancy):
        if not min_z <= c[2] <= max_z:
            continue
        n = int(round(size / res))
        i0 = int(round((c[0] - size / 2 - grid.origin[0]) / res))
        j0 = int(round((c[1] - size / 2 - grid.origin[1]) / res))
        for i in range(i0, i0 + n):
            for j in range(j0, j0 + n):
                if occ > tree.occupancy_thres:
                    out[j, i] = 100
                elif out[j, i] == -1:
                    out[j, i] = 0
    return grid, out


@pytest.mark.parametrize("band", [(-np.inf, np.inf), (0.3, 0.7)])
def test_the_projected_map_is_the_cell_by_cell_rule(tree, band):
    grid, expected = walked(tree, *band)
    np.testing.assert_array_equal(grid.data, expected)
    assert (grid.data == 100).any() and (grid.data == 0).any()


def test_the_projected_map_marks_the_walls_and_the_free_space_before_them(tree):
    grid = projection.project(tree)

    def cell(x, y):
        return grid.data[int((y - grid.origin[1]) // 0.2), int((x - grid.origin[0]) // 0.2)]
    assert cell(4.1, 0.1) == 100 and cell(2.1, 0.1) == 0


def test_semantic_cloud_colours_are_packed_rgb_bits():
    bits = views.packed_rgb(np.array([[1.0, 0.5, 0.0]])).view(np.uint32)
    assert bits[0] == (255 << 16) | (128 << 8)


def test_the_latest_queue_keeps_the_newest_and_returns_what_it_pushed_out():
    q = LatestQueue(2)
    assert q.put(1) is None and q.put(2) is None
    assert q.put(3) == 1
    assert q.get(0) == 2 and q.get(0) == 3 and q.get(0.01) is None
