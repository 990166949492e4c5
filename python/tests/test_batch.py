"""Batch mapping into tiles on a 2-worker Dask cluster: the tiled map equals the sequential map
(clamped once at the end), does not depend on the worker count, survives failing tasks, opens
as a TiledMap whose queries read only their tiles; the command line writes tiles and one .ot."""
import dataclasses
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import evidential_octomap as eo
from evidential_octomap import batch, tiles
from conftest import KITTI, REPO

distributed = pytest.importorskip("distributed")
CLASSES = str(REPO / "config" / "classes_semantickitti.yaml")
# A 30 m range and 6.4 m tiles: many tiles, some merged while later chunks are still mapping.
JOB = batch.MappingJob(data=str(KITTI), classes=CLASSES, config={"max_range": 30.0})
SCANS = 4
EDGE = 6.4


@pytest.fixture(scope="module")
def client():
    with batch.local_client(2) as c:
        yield c
        c.cluster.close()


def sequential_map(job, scans):
    """One process, scan after scan; clamped once at the end."""
    tree = batch.map_chunk(dataclasses.replace(job, unclamped=True), 0, scans).tree
    tree.clamp_occupancy()
    return tree


@pytest.fixture(scope="module")
def sequential():
    return sequential_map(JOB, SCANS)


@pytest.fixture(scope="module")
def tiled(client, tmp_path_factory):
    out = tmp_path_factory.mktemp("batch") / "tiles"
    batch.map_sequence(client, JOB, str(out), scans=SCANS, chunk_size=1, tile_edge=EDGE,
                       progress=False)
    return out


def assert_same_map(tree, reference):
    """Every leaf of the reference answers alike in `tree`, and both have the same leaves."""
    leaves = reference.leaves()
    got = tree.query(leaves.centers)
    np.testing.assert_array_equal(got.labels, leaves.labels)
    np.testing.assert_array_equal(got.occupied, leaves.occupancy > 0.5)
    np.testing.assert_allclose(got.belief, reference.query(leaves.centers).belief, atol=1e-5)
    assert got.known.all()
    assert tree.num_leaves == reference.num_leaves
    assert tree.num_semantic_nodes == reference.num_semantic_nodes


def test_tiled_map_equals_the_sequential_map(tiled, sequential, kitti_scans):
    tiled_map = eo.TiledMap(str(tiled))
    assert len(tiled_map.tiles) > 8 and tiled_map.tile_edge == pytest.approx(EDGE)
    assert not (tiled / ".work").exists()  # the chunks' tiles are gone
    whole = tiled_map.global_map()
    assert_same_map(whole, sequential)
    assert whole.mean_point_log_evidence == pytest.approx(sequential.mean_point_log_evidence)
    # OctoMap's clamp after every scan changes log-odds, never a label.
    clamped = batch.map_chunk(JOB, 0, SCANS).tree
    points = np.concatenate([s.points_world() for s, _ in kitti_scans[:3]])
    np.testing.assert_array_equal(whole.query(points).labels, clamped.query(points).labels)


def test_streamed_global_map_is_the_global_map(tiled, tmp_path):
    tiled_map = eo.TiledMap(str(tiled))
    tiled_map.write_global_map(str(tmp_path / "streamed.ot"))
    tiled_map.global_map().save(str(tmp_path / "whole.ot"))
    assert (tmp_path / "streamed.ot").read_bytes() == (tmp_path / "whole.ot").read_bytes()


def test_tiled_queries_read_only_their_tiles(tiled, sequential):
    tiled_map = eo.TiledMap(str(tiled))
    leaves = sequential.leaves()
    some = leaves.centers[leaves.labels >= 0][::50]
    got, expected = tiled_map.query(some), sequential.query(some)
    np.testing.assert_array_equal(got.labels, expected.labels)
    np.testing.assert_array_equal(got.occupied, expected.occupied)
    near = eo.TiledMap(str(tiled))
    near.query(np.array([some[0], some[0] + 0.01]))  # two points in one voxel
    assert near.tiles_loaded == 2  # the settings' tile, then the one both points lie in
    assert near.query(np.array([[5000.0, 0.0, 0.0]])).known.tolist() == [False]


def test_result_does_not_depend_on_the_worker_count(tiled, tmp_path):
    with batch.local_client(1) as one:
        batch.map_sequence(one, JOB, str(tmp_path / "alone"), scans=SCANS, chunk_size=1,
                           tile_edge=EDGE, progress=False)
        one.cluster.close()
    eo.TiledMap(str(tmp_path / "alone")).write_global_map(str(tmp_path / "alone.ot"))
    eo.TiledMap(str(tiled)).write_global_map(str(tmp_path / "two.ot"))
    assert (tmp_path / "alone.ot").read_bytes() == (tmp_path / "two.ot").read_bytes()


def test_chunks_of_several_scans_give_the_same_map(client, sequential, tmp_path):
    batch.map_sequence(client, JOB, str(tmp_path / "t"), scans=SCANS, chunk_size=3,
                       tile_edge=EDGE, progress=False)
    assert_same_map(eo.TiledMap(str(tmp_path / "t")).global_map(), sequential)


def test_schedule_merges_a_tile_once_every_chunk_within_reach_is_mapped():
    boxes = [((0, 0, 0), (1, 1, 1)), ((1, 1, 1), (2, 2, 2)), ((5, 5, 5), (6, 6, 6))]
    schedule = batch.TileSchedule(boxes)
    chunk = lambda i, t: tiles.ChunkTiles(i, 1, frozenset(t), frozenset(), 0.0, 0)  # noqa: E731
    assert schedule.mapped(chunk(0, [(0, 0, 0), (1, 1, 1)])) == [((0, 0, 0), [0])]
    assert schedule.mapped(chunk(2, [(5, 5, 5)])) == [((5, 5, 5), [2])]
    assert schedule.mapped(chunk(1, [(1, 1, 1)])) == [((1, 1, 1), [0, 1])]
    with pytest.raises(RuntimeError, match="beyond the reach"):
        batch.TileSchedule(boxes).mapped(chunk(0, [(4, 4, 4)]))


def fails_once_per_chunk(job, index, start, stop, work, depth, marker_dir):
    marker = Path(marker_dir) / f"chunk{start}"
    if not marker.exists():
        marker.touch()
        raise RuntimeError(f"injected failure of chunk {start}")
    return tiles.map_chunk_to_tiles(job, index, start, stop, work, depth)


def test_failing_chunks_are_retried(client, tiled, tmp_path):
    markers = tmp_path / "markers"
    markers.mkdir()
    flaky = lambda *a: fails_once_per_chunk(*a, str(markers))  # noqa: E731
    batch.map_sequence(client, JOB, str(tmp_path / "t"), scans=SCANS, chunk_size=1, retries=1,
                       tile_edge=EDGE, progress=False, chunk_fn=flaky)
    assert len(list(markers.iterdir())) == SCANS  # every chunk failed once
    eo.TiledMap(str(tmp_path / "t")).write_global_map(str(tmp_path / "a.ot"))
    eo.TiledMap(str(tiled)).write_global_map(str(tmp_path / "b.ot"))
    assert (tmp_path / "a.ot").read_bytes() == (tmp_path / "b.ot").read_bytes()
    (tmp_path / "x").mkdir()
    with pytest.raises(RuntimeError, match="injected failure"):
        batch.map_sequence(client, JOB, str(tmp_path / "u"), scans=SCANS, chunk_size=1,
                           retries=0, tile_edge=EDGE, progress=False,
                           chunk_fn=lambda *a: fails_once_per_chunk(*a, str(tmp_path / "x")))


def test_a_directory_with_files_is_refused(client, tmp_path):
    (tmp_path / "old.ot").write_bytes(b"")
    with pytest.raises(ValueError, match="not empty"):
        batch.map_sequence(client, JOB, str(tmp_path), scans=1, progress=False)


def robot(tmp_path, name, stems):
    """A sequence of some of the bundled scans (all poses: one world frame)."""
    root = tmp_path / name
    for sub, ext in (("velodyne", "bin"), ("labels", "label"), ("predictions", "label")):
        (root / sub).mkdir(parents=True)
        for stem in stems:
            shutil.copy(KITTI / sub / f"{stem:06d}.{ext}", root / sub)
    for name in ("poses.txt", "calib.txt"):
        shutil.copy(KITTI / name, root)
    return root


def one_robot_driving(sequences):
    """The sequences' scans inserted into one map, one sequence after the other."""
    classes = eo.ClassTable.load(CLASSES)
    tree = eo.EvidentialOcTree(JOB.resolution, classes, JOB.semantic_config())
    batch.set_unbounded(tree, True)
    for data in sequences:
        dataset = eo.Dataset.open(str(data), classes)
        for i in range(len(dataset)):
            scan = dataset.load(i)
            evidence = eo.derive_evidence(scan, classes.num_classes, JOB.evidence, JOB.magnitude)
            tree.insert_scan(scan.points_world(), evidence, origin=scan.origin)
    batch.set_unbounded(tree, False)
    tree.clamp_occupancy()
    return tree


def test_two_robots_merge_into_the_map_one_robot_driving_both_makes(client, tmp_path):
    a, b = robot(tmp_path, "a", [0, 1, 2]), robot(tmp_path, "b", [1, 2, 3, 4])  # they overlap
    out = tmp_path / "fleet"
    batch.map_sequence(client, dataclasses.replace(JOB, data=str(a)), str(out), chunk_size=2,
                       tile_edge=EDGE, progress=False, then=[str(b)])
    assert_same_map(eo.TiledMap(str(out)).global_map(), one_robot_driving([a, b]))


def test_command_line_writes_tiles_and_the_global_map(tmp_path):
    out, whole = tmp_path / "tiles", tmp_path / "map.ot"
    run = subprocess.run([sys.executable, "-m", "evidential_octomap.batch", "--data", str(KITTI),
                          "--classes", CLASSES, "--out", str(out), "--global-map", str(whole),
                          "--scans", "2", "--chunk-size", "1", "--workers", "2",
                          "--set", "max_range=30"],
                         check=True, capture_output=True, text=True)
    tiles_written = len(eo.TiledMap(str(out)).tiles)
    assert "DERIVED" in run.stderr
    assert f"2/2 scans mapped, {tiles_written}/{tiles_written} tiles merged" in run.stderr
    assert f"wrote {out}: {tiles_written} tiles from 2 chunks of 2 scans" in run.stdout
    assert eo.load(str(whole)).num_semantic_nodes > 0
    bad = subprocess.run([sys.executable, "-m", "evidential_octomap.batch", "--data", str(KITTI),
                          "--classes", CLASSES, "--out", str(out), "--set", "colour=red"],
                         capture_output=True, text=True)
    assert bad.returncode != 0 and "--set colour=red" in bad.stderr


def test_unclamped_chunks_keep_unbounded_log_odds_until_the_end():
    tree = batch.map_chunk(dataclasses.replace(JOB, unclamped=True), 0, 1).tree
    default = eo.EvidentialOcTree(0.2)
    assert tree.clamping_thres_max == pytest.approx(default.clamping_thres_max)  # can be sent
    batch.set_unbounded(tree, True)
    for _ in range(3):  # 8 copies of the scan: log-odds far beyond OctoMap's bounds
        tree.merge(tree.copy())
    batch.set_unbounded(tree, False)
    sent = eo.EvidentialOcTree.from_bytes(tree.to_bytes())  # how Dask moves chunk maps
    assert sent.leaves().occupancy.max() > default.clamping_thres_max
    sent.clamp_occupancy()
    clamped = sent.leaves().occupancy
    assert clamped.max() == pytest.approx(default.clamping_thres_max)
    assert clamped.min() == pytest.approx(default.clamping_thres_min)
