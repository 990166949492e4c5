"""The module on the bundled SemanticKITTI scans (evidence derived from hard labels): metrics
recomputed in numpy, parity with the CLI, and inserts that release the GIL."""
import json
import os
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import evidential_octomap as eo
from conftest import KITTI, REPO


def mapped(kitti_scans, kitti_classes, count):
    tree = eo.EvidentialOcTree(0.2, kitti_classes)
    for scan, evidence in kitti_scans[:count]:
        tree.insert_scan(scan.points_world(), evidence, origin=scan.origin)
    return tree


def test_dataset_reader(kitti, kitti_scans):
    assert len(kitti) == 10 and kitti.has_labels and kitti.has_predictions
    scan, evidence = kitti_scans[1]
    assert scan.name == "000001" and scan.points.shape == (len(scan), 3)
    assert scan.gt.shape == scan.predicted.shape == (len(scan),)
    np.testing.assert_array_equal(scan.pose, kitti.pose(1))
    world = scan.points.astype(np.float64) @ scan.pose[:3, :3].T + scan.pose[:3, 3]
    np.testing.assert_allclose(scan.points_world(), world, atol=1e-4)
    # onehot, E = 20: the predicted class gets 20, every other class 0.
    assert evidence.shape == (len(scan), 20)
    np.testing.assert_array_equal(evidence.argmax(axis=1), scan.predicted)
    assert (evidence.sum(axis=1) == 20.0).all()
    assert eo.evidence_is_derived("onehot") and not eo.evidence_is_derived("file")
    with pytest.raises(RuntimeError, match="no evidence|has none"):
        eo.derive_evidence(scan, 20, "file")
    with pytest.raises(IndexError, match="scan 10 of 10"):
        kitti.load(10)


def test_map_metrics_equal_a_numpy_recomputation(kitti_scans, kitti_classes):
    tree = mapped(kitti_scans, kitti_classes, 2)
    scan, evidence = kitti_scans[2]
    keep = scan.gt != kitti_classes.ignore_class
    points, gt = scan.points_world()[keep], scan.gt[keep]
    metrics = eo.evaluate_map(tree, points, gt, kitti_classes.ignore_class)
    answer = tree.query(points)
    labelled = answer.labels >= 0
    quality = metrics.quality
    assert quality.queries == len(gt) and quality.labelled == labelled.sum()
    assert metrics.occupied == answer.occupied.sum()
    assert metrics.occupancy_coverage == pytest.approx(answer.occupied.mean())
    assert metrics.semantic_coverage == pytest.approx(labelled.mean())
    assert quality.acc_all == pytest.approx((answer.labels == gt).mean())
    assert quality.acc_labelled == pytest.approx((answer.labels == gt)[labelled].mean())
    ious = []
    for c in np.unique(gt):
        tp = ((answer.labels == c) & (gt == c)).sum()
        ious.append(tp / ((answer.labels == c) | (gt == c)).sum())
    assert quality.miou_all == pytest.approx(np.mean(ious))
    assert quality.confusion_all.sum() == len(gt)
    assert quality.confusion_all[:, -1].sum() == (~labelled).sum()
    # Brier of the projected probabilities b + u / C (uniform without a label).
    p = answer.belief + answer.uncertainty[:, None] / 20
    p[~labelled] = 1.0 / 20
    assert quality.brier == pytest.approx(((p - np.eye(20)[gt]) ** 2).sum(axis=1).mean(), rel=1e-4)
    assert list(quality.error_detection) == ["u", "conflict", "1-max_p", "dissonance",
                                            "error_probability"]
    assert 0 <= quality.error_detection["u"].auroc <= 1
    predicted = scan.predicted[keep]
    hard = eo.evaluate_input(gt, predicted, num_classes=20, ignore_class=kitti_classes.ignore_class)
    assert hard.acc_all == pytest.approx((predicted == gt).mean())
    soft = eo.evaluate_input(gt, evidence=evidence[keep], num_classes=20,
                             ignore_class=kitti_classes.ignore_class)
    assert soft.acc_all == pytest.approx((evidence[keep].argmax(axis=1) == gt).mean())
    with pytest.raises(ValueError, match="predicted classes or its evidence"):
        eo.evaluate_input(gt, num_classes=20)


def cli_binary():
    path = Path(os.environ.get("EVIDENTIAL_OCTOMAP_CLI",
                               REPO / "build" / "core" / "src" / "tools" / "evidential_octomap"))
    return path if path.is_file() else None


@pytest.mark.skipif(cli_binary() is None, reason="the CLI is built by scripts/test.sh (build/core)")
def test_python_maps_exactly_what_the_cli_maps(tmp_path, kitti_scans, kitti_classes):
    subprocess.run([str(cli_binary()), "map", "--data", str(KITTI), "--classes",
                    str(REPO / "config" / "classes_semantickitti.yaml"), "--out", str(tmp_path),
                    "--scans", "2", "--no-render", "-q", "--no-calibration"], check=True, capture_output=True)
    cli_map = eo.load(tmp_path / "map.ot")
    tree = mapped(kitti_scans, kitti_classes, 2)
    points = kitti_scans[0][0].points_world()
    a, b = tree.query(points), cli_map.query(points)
    np.testing.assert_array_equal(a.belief, b.belief)
    np.testing.assert_array_equal(a.occupied, b.occupied)
    assert tree.num_leaves == cli_map.num_leaves


def test_insert_scan_releases_the_gil(kitti_scans, kitti_classes):
    """While one thread inserts a real scan, the main thread keeps running Python."""
    scan, evidence = kitti_scans[0]
    points = scan.points_world()
    tree = eo.EvidentialOcTree(0.2, kitti_classes)
    span = {}

    def insert():
        span["start"] = time.monotonic()
        tree.insert_scan(points, evidence, origin=scan.origin)
        span["end"] = time.monotonic()

    worker = threading.Thread(target=insert)
    ticks = []
    worker.start()
    while worker.is_alive():
        ticks.append(time.monotonic())
    worker.join()
    during = [t for t in ticks if span["start"] < t < span["end"]]
    assert len(during) > 100  # with the GIL held the main thread could not run at all


@pytest.mark.skipif(cli_binary() is None, reason="the CLI is built by scripts/test.sh (build/core)")
def test_compare_voxel_majority_iou_equals_a_numpy_recomputation(tmp_path, kitti_scans,
                                                                 kitti_classes):
    """compare.json's per-class voxel_majority_iou: the majority of the mapped points'
    predictions in each query's 0.2 m voxel (ties to the lowest class, ignore class not
    counted), IoU over all queries."""
    subprocess.run([str(cli_binary()), "compare", "-q", "--no-rellis", "--scans", "2",
                    "--sources", "onehot", "--protocols", "reconstruction", "--variants",
                    "dempster", "--bootstrap-replicates", "10", "--data", str(KITTI), "--classes",
                    str(REPO / "config" / "classes_semantickitti.yaml"), "--out", str(tmp_path)],
                   check=True, capture_output=True)
    with open(tmp_path / "compare.json") as f:
        per_class = json.load(f)["runs"][0]["per_class"]
    ignore, C = kitti_classes.ignore_class, kitti_classes.num_classes
    points = np.vstack([s.points_world() for s, _ in kitti_scans[:2]]).astype(np.float32)
    predicted = np.concatenate([s.predicted for s, _ in kitti_scans[:2]])
    gt = np.concatenate([s.gt for s, _ in kitti_scans[:2]])
    keys = np.floor(points.astype(np.float64) * (1 / 0.2)).astype(np.int64)  # OctoMap coordToKey
    _, voxel = np.unique(keys, axis=0, return_inverse=True)
    voxel = voxel.ravel()
    counts = np.zeros((voxel.max() + 1, C), np.int64)
    counted = predicted != ignore
    np.add.at(counts, (voxel[counted], predicted[counted]), 1)
    majority = np.where(counts.max(axis=1) > 0, counts.argmax(axis=1), -1)[voxel]
    query = gt != ignore
    checked = 0
    for c in per_class:
        k = c["class"]
        union = ((majority == k) | (gt == k))[query].sum()
        if union == 0:
            assert c["voxel_majority_iou"] is None
            continue
        expected = ((majority == k) & (gt == k))[query].sum() / union
        assert c["voxel_majority_iou"] == pytest.approx(expected, abs=1e-3), c["name"]
        checked += 1
    assert checked >= 8
