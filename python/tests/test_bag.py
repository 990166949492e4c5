"""ROS 1 and ROS 2 bags written by `python -m evidential_octomap.bag write` from the bundled scans
(3 of them, with TF and one cloud outside the TF buffer), mapped by `... bag map`: the map equals
the one the Python API makes from the same dataset directly and the CLI's `evidential_octomap
map`; the outside-buffer cloud is reported and skipped; raw clouds go through a model."""
import json
import subprocess
import sys

import numpy as np
import pytest

pytest.importorskip("rosbags", reason="the bags extra: pip install '.[bags]'")

import evidential_octomap as eo  # noqa: E402
from evidential_octomap import bag  # noqa: E402
from evidential_octomap.models import DatasetPredictions, LearnedEvidence  # noqa: E402
from bag_helpers import assert_same_map, compare_leaves, tf_exact_dataset  # noqa: E402
from conftest import KITTI, REPO  # noqa: E402
from test_kitti import cli_binary  # noqa: E402

SCANS = 3
CLASSES = REPO / "config" / "classes_semantickitti.yaml"
FORMATS = {"ros1": dict(ros2=False), "mcap": dict(ros2=True, storage="mcap"),
           "sqlite3": dict(ros2=True, storage="sqlite3")}


@pytest.fixture(scope="module")
def exact(tmp_path_factory, kitti_classes):
    return tf_exact_dataset(KITTI, tmp_path_factory.mktemp("exact"), kitti_classes, SCANS)


@pytest.fixture(scope="module")
def bags(tmp_path_factory, exact, kitti_classes):
    out = tmp_path_factory.mktemp("bags")
    written = {}
    for name, kind in FORMATS.items():
        path = out / ("kitti.bag" if name == "ros1" else f"kitti_{name}")
        info = bag.write_bag(exact, path, kitti_classes,
                             bag.WriteOptions(outside_buffer=True, **kind), str(CLASSES))
        written[name] = (path, info)
    return written


@pytest.fixture(scope="module")
def direct(exact, kitti_classes):
    """The Python API's map of the same directory (onehot E = 20, as the bag's evidence)."""
    dataset = eo.Dataset.open(str(exact), kitti_classes)
    tree = eo.EvidentialOcTree(0.2, kitti_classes)
    for i in range(SCANS):
        scan = dataset.load(i)
        tree.insert_scan(scan.points_world(), eo.derive_evidence(scan, 20), origin=scan.origin)
    return tree


@pytest.fixture(scope="module")
def mapped(bags, kitti_classes):
    """Each bag's evidence topic mapped (ROS 2 MCAP by the command line, the others by map_bag)."""
    maps = {}
    for name, (path, _) in bags.items():
        if name == "mcap":
            out = path.parent / "out_mcap"
            run = subprocess.run(
                [sys.executable, "-m", "evidential_octomap.bag", "map", str(path), "--classes",
                 str(CLASSES), "--frame", "map", "--out", str(out), "--topic",
                 "/velodyne_points/evidence", "-q"], capture_output=True, text=True)
            assert run.returncode == 0, run.stderr
            maps[name] = (eo.load(out / "map.ot"), json.loads((out / "summary.json").read_text()),
                          out, run.stdout)
        else:
            options = bag.MapOptions(topic="/velodyne_points/evidence")
            result = bag.map_bag(path, kitti_classes, options)
            maps[name] = (result.tree, result.summary, None, "")
    return maps


@pytest.mark.parametrize("name", list(FORMATS))
def test_a_bag_maps_to_the_map_the_python_api_makes_from_the_dataset(name, mapped, direct):
    tree, summary, _, _ = mapped[name]
    assert summary["scans_mapped"] == SCANS and summary["clouds"] == SCANS + 1
    assert summary["evidence_sources"] == {"evidence[20]": SCANS}
    assert summary["evidence_declared"].startswith("derived: onehot evidence of magnitude 20")
    assert_same_map(compare_leaves(direct.leaves(), tree.leaves()))


@pytest.mark.parametrize("name", list(FORMATS))
def test_the_cloud_outside_the_tf_buffer_is_reported_and_skipped(name, mapped, bags):
    _, summary, _, _ = mapped[name]
    info = bags[name][1]
    (dropped,) = summary["dropped"]
    assert dropped["index"] == SCANS and dropped["stamp_ns"] == info["outside_buffer_stamp_ns"]
    reason = dropped["reason"]
    assert "cannot transform 'velodyne' to 'map' at 2.200000000 s" in reason
    assert "1.000 s after the last transform 'map' -> 'base_link'" in reason
    assert "the buffer holds /tf from 1.000000000 s to 1.200000000 s" in reason


def test_the_command_line_writes_the_map_the_summary_and_the_pictures(mapped):
    _, summary, out, stdout = mapped["mcap"]
    assert summary["format"] == "ROS 2 bag (mcap)" and summary["scans_per_s"] > 0
    assert "mapped 3 of 4 clouds" in stdout and "dropped cloud 3" in stdout
    md = (out / "summary.md").read_text()
    assert "| 3 | 2.200000000 | velodyne | cannot transform" in md
    expected = {"map.ot", "summary.json", "summary.md"}
    if hasattr(eo._core, "render_top_down"):
        expected |= {"semantic.png", "uncertainty.png"}
        assert (out / "semantic.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert set(summary["outputs"]) == expected and all((out / f).is_file() for f in expected)


@pytest.mark.skipif(cli_binary() is None, reason="the CLI is built by scripts/test.sh (build/core)")
def test_the_bag_map_equals_the_clis_map_of_the_dataset(tmp_path, exact, mapped):
    subprocess.run([str(cli_binary()), "map", "--data", str(exact), "--classes", str(CLASSES),
                    "--out", str(tmp_path), "--scans", str(SCANS), "--no-render", "-q",
                    "--no-calibration"], check=True, capture_output=True)
    cli = eo.load(tmp_path / "map.ot")
    assert_same_map(compare_leaves(cli.leaves(), mapped["ros1"][0].leaves()))


def test_raw_clouds_without_a_semantic_field_need_a_model(bags, kitti_classes):
    options = bag.MapOptions(topic="/velodyne_points", max_clouds=1)
    summary = bag.map_bag(bags["ros1"][0], kitti_classes, options).summary
    assert summary["scans_mapped"] == 0
    (dropped,) = summary["dropped"]
    assert dropped["reason"].startswith("no semantic field")
    assert "(fields: x, y, z, intensity)" in dropped["reason"] and "--model" in dropped["reason"]


def test_raw_clouds_through_the_learned_model_map_as_the_learned_evidence_does(
        bags, exact, kitti_classes):
    model_path = REPO / "config" / "learned" / "semantickitti.model"
    model = LearnedEvidence(model_path, DatasetPredictions(exact, kitti_classes))
    options = bag.MapOptions(topic="/velodyne_points", max_clouds=1)
    result = bag.map_bag(bags["mcap"][0], kitti_classes, options, model=model)
    assert result.summary["scans_mapped"] == 1
    assert next(iter(result.summary["evidence_sources"])).startswith("model: learned")
    scan = eo.Dataset.open(str(exact), kitti_classes).load(0)
    evidence = eo.LearnedEvidenceModel.load(str(model_path)).evidence(
        scan.points, scan.remission, scan.predicted)
    assert not np.array_equal(evidence.argmax(1), scan.predicted)  # not just the hard labels
    tree = eo.EvidentialOcTree(0.2, kitti_classes)
    tree.insert_scan(scan.points_world(), evidence, origin=scan.origin)
    assert_same_map(compare_leaves(tree.leaves(), result.tree.leaves()))


def test_a_users_model_file_is_called_with_the_points_and_fields(tmp_path, bags, kitti_classes):
    (tmp_path / "my_model.py").write_text(
        "import numpy as np\n"
        "def evidence(points, fields):\n"
        "    e = np.zeros((len(points), 20), np.float32)\n"
        "    e[:, 9] = 5.0 + fields['intensity']  # 'road' everywhere\n"
        "    return e\n")
    run = subprocess.run(
        [sys.executable, "-m", "evidential_octomap.bag", "map", str(bags["sqlite3"][0]),
         "--classes", str(CLASSES), "--out", str(tmp_path / "out"), "--topic", "/velodyne_points",
         "--model", f"{tmp_path / 'my_model.py'}:evidence", "--max-clouds", "1", "--no-render",
         "-q"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    tree = eo.load(tmp_path / "out" / "map.ot")
    labels = tree.leaves(occupied_only=True).labels
    assert set(np.unique(labels[labels >= 0])) == {9}


def test_a_missing_topic_is_refused_naming_the_cloud_topics(bags, kitti_classes):
    with pytest.raises(ValueError, match="no PointCloud2 topic '/nope'.*/velodyne_points"):
        bag.map_bag(bags["ros1"][0], kitti_classes, bag.MapOptions(topic="/nope"))
    with pytest.raises(ValueError,
                       match=r"2 PointCloud2 topics.*which one should be mapped\? "
                             r"Choose it with --topic"):
        bag.map_bag(bags["ros1"][0], kitti_classes, bag.MapOptions())


def _calibration(tmp_path, classes=""):
    path = tmp_path / "calibration.yaml"
    path.write_text("calibration_version: 2\ncalibration_rule: dempster\n" + classes +
                    "evidence_cap: -1\nerror_model_terms: [intercept, vacuity]\n"
                    "error_model_weights: [0.5, 2.0]\n")
    return path


def test_network_evidence_without_a_calibration_gets_one_note(tmp_path, mapped, capsys):
    tree, summary, _, _ = mapped["ros1"]
    network = dict(summary, evidence_declared="network evidence: the dataset's evidence files")
    bag.note_if_uncalibrated(bag.BagMap(tree, summary))  # derived one-hot: nothing to calibrate
    assert capsys.readouterr().err == ""
    bag.note_if_uncalibrated(bag.BagMap(tree, network))
    err = capsys.readouterr().err
    assert "uncalibrated" in err and "evidential_octomap calibrate" in err
    calibrated = eo.EvidentialOcTree(0.2, 3)
    calibrated.apply_calibration(eo.read_calibration(str(_calibration(tmp_path))))
    bag.note_if_uncalibrated(bag.BagMap(calibrated, network))
    assert capsys.readouterr().err == ""


def test_map_reads_a_calibration_file_and_refuses_one_of_other_classes(tmp_path, bags):
    path = bags["mcap"][0]
    command = [sys.executable, "-m", "evidential_octomap.bag", "map", str(path), "--classes",
               str(CLASSES), "--out", str(tmp_path / "out"), "--topic",
               "/velodyne_points/evidence", "--no-render", "-q", "--calibration"]
    run = subprocess.run(command + [str(_calibration(tmp_path))], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    other = _calibration(tmp_path, "calibration_classes: [road, grass]\n")
    run = subprocess.run(command + [str(other)], capture_output=True, text=True)
    assert run.returncode != 0 and "fitted for 2 classes [road, grass]" in run.stderr
