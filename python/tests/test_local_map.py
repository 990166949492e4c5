"""LocalMap from Python: tiles leave for disk behind the sensor, queries of points on them answer
as the whole map does, and global_map() equals the map built without tiles (synthetic walls
along a 60 m path)."""
import numpy as np
import pytest

import evidential_octomap as eo
from conftest import wall

CLASSES = ["ground", "obstacle", "vegetation"]


def config():
    return eo.SemanticConfig(max_range=8.0)  # reach 10.35 m at 0.2 m


def walls_along(x):
    """A wall 4 m ahead of a sensor at (x, 0, 0.5), class 1, or 2 every third metre."""
    points, evidence = wall(x=4.0, label=1 + (int(x) % 3 == 0))
    points[:, 0] += x
    return points, evidence


def map_out(metres, tile_directory):
    whole = eo.EvidentialOcTree(0.2, CLASSES, config())
    resident = eo.EvidentialOcTree(0.2, CLASSES, config())
    local = eo.LocalMap(resident, str(tile_directory), 12.0)
    for x in range(metres + 1):
        points, evidence = walls_along(float(x))
        origin = (float(x) + 0.05, 0.1, 0.5)
        whole.insert_scan(points, evidence, origin=origin)
        local.insert_scan(points, evidence, origin=origin)
    return whole, resident, local


def test_queries_of_points_on_tiles_on_disk_answer_as_the_whole_map(tmp_path):
    whole, resident, local = map_out(60, tmp_path)
    assert local.tiles_on_disk > 0 and resident.num_leaves < whole.num_leaves
    x, z = np.meshgrid(np.arange(4.1, 64.0, 0.2), [0.1, 0.5, 0.9])
    points = np.stack([x.ravel(), np.full(x.size, 0.1), z.ravel()], axis=1).astype(np.float32)
    want, got = whole.query(points), local.query(points)
    assert (want.labels >= 0).sum() > 300
    np.testing.assert_array_equal(got.labels, want.labels)
    np.testing.assert_array_equal(got.known, want.known)
    np.testing.assert_array_equal(got.occupied, want.occupied)
    np.testing.assert_allclose(got.uncertainty, want.uncertainty, rtol=1e-6)
    np.testing.assert_allclose(got.belief, want.belief, rtol=1e-6, atol=1e-7)
    # The resident map alone no longer knows the start of the path.
    start = points[points[:, 0] < 20.0]
    assert not resident.query(start).known.any()
    assert whole.query(start).known.all()


def test_global_map_equals_the_map_built_without_tiles(tmp_path):
    whole, resident, local = map_out(40, tmp_path)
    assert local.tiles_written > 0 and resident.num_leaves < whole.num_leaves
    centres = whole.leaves().centers  # every voxel the whole map knows
    want, got = whole.query(centres), local.global_map().query(centres)
    assert got.known.all()
    np.testing.assert_array_equal(got.labels, want.labels)
    np.testing.assert_array_equal(got.occupied, want.occupied)
    np.testing.assert_allclose(got.belief, want.belief, rtol=1e-6, atol=1e-7)


def test_a_radius_below_the_reach_is_refused(tmp_path):
    tree = eo.EvidentialOcTree(0.2, CLASSES, config())
    assert eo.LocalMap.reach(tree) == pytest.approx(10.35, abs=0.01)
    with pytest.raises(ValueError, match="reach of a scan"):
        eo.LocalMap(tree, str(tmp_path), 9.0)
