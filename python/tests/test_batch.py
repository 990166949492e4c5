"""Batch mapping on a 2-worker Dask cluster: the merged map equals the sequential one, does not
depend on the worker count, survives failing tasks; the command line writes the .ot."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import evidential_octomap as eo
from evidential_octomap import batch
from conftest import KITTI, REPO

distributed = pytest.importorskip("distributed")
CLASSES = str(REPO / "config" / "classes_semantickitti.yaml")
JOB = batch.MappingJob(data=str(KITTI), classes=CLASSES)
SCANS = 3


@pytest.fixture(scope="module")
def client():
    with batch.local_client(2) as c:
        yield c
        c.cluster.close()


@pytest.fixture(scope="module")
def sequential(kitti_scans, kitti_classes):
    tree = eo.EvidentialOcTree(0.2, kitti_classes)
    for scan, evidence in kitti_scans[:SCANS]:
        tree.insert_scan(scan.points_world(), evidence, origin=scan.origin)
    return tree


@pytest.fixture(scope="module")
def merged(client):
    return batch.map_sequence(client, JOB, scans=SCANS, chunk_size=1, progress=False)


def test_merged_map_equals_the_sequential_map(merged, sequential, kitti_scans):
    points = np.concatenate([s.points_world() for s, _ in kitti_scans[:SCANS]])
    a, b = sequential.query(points), merged.query(points)
    np.testing.assert_array_equal(a.labels, b.labels)
    np.testing.assert_allclose(a.belief, b.belief, atol=1e-5)
    np.testing.assert_array_equal(a.known, b.known)
    assert merged.num_leaves == sequential.num_leaves
    assert merged.num_semantic_nodes == sequential.num_semantic_nodes


def test_result_does_not_depend_on_the_worker_count(merged):
    with batch.local_client(1) as one:
        alone = batch.map_sequence(one, JOB, scans=SCANS, chunk_size=1, progress=False)
        one.cluster.close()
    assert alone.to_bytes() == merged.to_bytes()


def test_in_order_merge_refuses_chunks_that_are_not_neighbours():
    first, third = batch.map_chunk(JOB, 0, 1), batch.map_chunk(JOB, 2, 3)
    with pytest.raises(ValueError, match="neighbours"):
        batch.merge_in_order(first, third)


def fails_once_per_chunk(job, start, stop, marker_dir):
    marker = Path(marker_dir) / f"chunk{start}"
    if not marker.exists():
        marker.touch()
        raise RuntimeError(f"injected failure of chunk {start}")
    return batch.map_chunk(job, start, stop)


def test_failing_chunks_are_retried(client, merged, tmp_path):
    flaky = lambda job, start, stop: fails_once_per_chunk(job, start, stop, str(tmp_path))  # noqa
    tree = batch.map_sequence(client, JOB, scans=SCANS, chunk_size=1, retries=1, progress=False,
                              chunk_fn=flaky)
    assert len(list(tmp_path.iterdir())) == SCANS  # every chunk failed once
    assert tree.to_bytes() == merged.to_bytes()
    tmp_path.joinpath("x").mkdir()
    with pytest.raises(RuntimeError, match="injected failure"):
        batch.map_sequence(client, JOB, scans=SCANS, chunk_size=1, retries=0, progress=False,
                           chunk_fn=lambda j, a, b: fails_once_per_chunk(j, a, b, str(tmp_path / "x")))


def test_command_line_writes_the_merged_map(tmp_path):
    out = tmp_path / "batch" / "map.ot"
    run = subprocess.run([sys.executable, "-m", "evidential_octomap.batch", "--data", str(KITTI),
                          "--classes", CLASSES, "--out", str(out), "--scans", "2",
                          "--chunk-size", "1", "--workers", "2", "--unclamped-merge"],
                         check=True, capture_output=True, text=True)
    assert "DERIVED" in run.stderr and "2/2 chunks mapped, 1/1 merged" in run.stderr
    written = eo.load(out)
    assert f"wrote {out}: {written.num_leaves} leaves" in run.stdout
    assert written.num_semantic_nodes > 0
    bad = subprocess.run([sys.executable, "-m", "evidential_octomap.batch", "--data", str(KITTI),
                          "--classes", CLASSES, "--out", str(out), "--set", "colour=red"],
                         capture_output=True, text=True)
    assert bad.returncode != 0 and "--set colour=red" in bad.stderr


def test_unclamped_chunks_keep_unbounded_log_odds_until_the_end():
    import dataclasses

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
