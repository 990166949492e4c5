"""EvidentialOcTree from Python: insert, query, leaves, files, errors (synthetic wall)."""
import pickle

import numpy as np
import pytest

import evidential_octomap as eo
from conftest import wall

ORIGIN = (0.0, 0.0, 0.5)


def wall_tree(**config):
    tree = eo.EvidentialOcTree(0.2, ["ground", "obstacle", "vegetation"], eo.SemanticConfig(**config))
    points, evidence = wall()
    tree.insert_scan(points, evidence, origin=ORIGIN)
    return tree, points


def test_wall_voxels_take_the_class_of_their_evidence():
    tree, points = wall_tree()
    answer = tree.query(points)
    assert (answer.labels == 1).all()
    assert answer.occupied.all() and answer.known.all()
    assert answer.belief.shape == (len(points), 3) and answer.belief.dtype == np.float32
    # A subjective opinion: beliefs and uncertainty sum to one, u in (0, 1).
    np.testing.assert_allclose(answer.belief.sum(axis=1) + answer.uncertainty, 1.0, atol=1e-5)
    assert ((answer.uncertainty > 0) & (answer.uncertainty < 1)).all()
    # Every point brought the same class evidence: little of it disagreed.
    assert ((answer.conflict >= 0) & (answer.conflict < 0.5)).all()


def test_error_probability_is_one_minus_the_largest_projected_probability():
    tree, points = wall_tree()
    answer = tree.query(points)
    projected = answer.belief + answer.uncertainty[:, None] / 3
    np.testing.assert_allclose(answer.error_probability, 1.0 - projected.max(axis=1), atol=1e-6)
    unknown = tree.query(np.array([[50.0, 50.0, 50.0]], dtype=np.float32))
    assert unknown.labels[0] == -1 and unknown.error_probability[0] == 1.0  # no label


def test_disagreeing_evidence_raises_the_conflict():
    tree = eo.EvidentialOcTree(0.2, 3)
    points, car = wall(label=1)
    tree.insert_scan(points, car, origin=ORIGIN)
    agreeing = tree.query(points).conflict.copy()
    _, vegetation = wall(label=2)
    tree.insert_scan(points, vegetation, origin=ORIGIN)
    assert (tree.query(points).conflict > agreeing + 0.1).all()


def test_free_space_in_front_of_the_wall_is_known_and_free():
    tree, _ = wall_tree()
    answer = tree.query(np.array([[2.0, 0.0, 0.5]], dtype=np.float32))
    assert answer.known[0] and not answer.occupied[0]


def test_unobserved_points_are_vacuous():
    tree, _ = wall_tree()
    far = np.array([[50.0, 50.0, 50.0], [np.nan, 0, 0], [1e30, 0, 0]], dtype=np.float32)
    answer = tree.query(far)
    assert (answer.labels == -1).all() and (answer.uncertainty == 1.0).all()
    assert not answer.known.any() and not answer.occupied.any()
    assert (answer.belief == 0).all()


def test_leaves_agree_with_queries_at_their_centres():
    tree, _ = wall_tree()
    leaves = tree.leaves()
    assert len(leaves.centers) == tree.num_leaves
    answer = tree.query(leaves.centers)
    np.testing.assert_array_equal(answer.labels, leaves.labels)
    np.testing.assert_array_equal(answer.belief, leaves.belief)
    np.testing.assert_array_equal(answer.error_probability, leaves.error_probability)
    occupied = tree.leaves(occupied_only=True)
    assert (occupied.occupancy > 0.5).all() and len(occupied.sizes) < len(leaves.sizes)


def test_leaves_without_opinions_give_the_same_geometry_and_occupancy():
    tree, _ = wall_tree()
    every, bare = tree.leaves(), tree.leaves(opinions=False)
    np.testing.assert_array_equal(bare.centers, every.centers)
    np.testing.assert_array_equal(bare.sizes, every.sizes)
    np.testing.assert_array_equal(bare.occupancy, every.occupancy)
    assert len(bare.labels) == len(bare.error_probability) == 0 and bare.belief.shape == (0, 3)


def test_the_occupied_leaves_are_the_occupied_rows_of_every_leaf():
    """occupied_only skips free subtrees whole: it must still give every occupied leaf, in
    order, with the same values."""
    tree, _ = wall_tree()
    every, occupied = tree.leaves(), tree.leaves(occupied_only=True)
    rows = every.occupancy > tree.occupancy_thres
    assert 0 < rows.sum() < len(rows) / 4
    for name in ("centers", "sizes", "occupancy", "labels", "uncertainty", "conflict",
                 "error_probability", "belief"):
        np.testing.assert_array_equal(getattr(occupied, name), getattr(every, name)[rows])


def test_pose_input_equals_points_transformed_by_numpy():
    points_S, evidence = wall()
    yaw = 0.3
    T = np.eye(4)
    T[:2, :2] = [[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]]
    T[:3, 3] = [5.0, -2.0, 0.5]
    by_pose = eo.EvidentialOcTree(0.2, 3)
    by_pose.insert_scan(points_S, evidence, pose=T)
    points_W = (points_S.astype(np.float64) @ T[:3, :3].T + T[:3, 3]).astype(np.float32)
    by_origin = eo.EvidentialOcTree(0.2, 3)
    by_origin.insert_scan(points_W, evidence, origin=T[:3, 3])
    a, b = by_pose.query(points_W), by_origin.query(points_W)
    np.testing.assert_array_equal(a.belief, b.belief)
    assert by_pose.num_leaves == by_origin.num_leaves


def test_float64_and_strided_inputs_are_converted():
    points, evidence = wall()
    reference = eo.EvidentialOcTree(0.2, 3)
    reference.insert_scan(points, evidence, origin=ORIGIN)
    converted = eo.EvidentialOcTree(0.2, 3)
    padded = np.zeros((len(points), 5))
    padded[:, ::2][:, :3] = points  # a non-contiguous float64 view
    converted.insert_scan(padded[:, ::2][:, :3], evidence.astype(np.float64), origin=ORIGIN)
    np.testing.assert_array_equal(reference.query(points).belief, converted.query(points).belief)


def test_malformed_evidence_raises_and_changes_nothing():
    tree, points = wall_tree()
    before = (tree.num_leaves, tree.num_semantic_nodes)
    _, evidence = wall()
    with pytest.raises(ValueError, match=r"evidence has shape \(800, 2\), expected \(800, 3\)"):
        tree.insert_scan(points, evidence[:, :2], origin=ORIGIN)
    evidence[7, 2] = -1.0
    with pytest.raises(ValueError, match="point 7"):
        tree.insert_scan(points, evidence, origin=ORIGIN)
    evidence[7, 2] = np.nan
    with pytest.raises(ValueError, match="point 7"):
        tree.insert_scan(points, evidence, origin=ORIGIN)
    assert (tree.num_leaves, tree.num_semantic_nodes) == before


def test_origin_and_pose_are_exclusive():
    tree = eo.EvidentialOcTree(0.2, 3)
    points, evidence = wall()
    with pytest.raises(ValueError, match="exactly one of origin"):
        tree.insert_scan(points, evidence)
    with pytest.raises(ValueError, match="exactly one of origin"):
        tree.insert_scan(points, evidence, origin=ORIGIN, pose=np.eye(4))


def test_bad_construction_and_config_raise_with_the_message():
    with pytest.raises(ValueError, match="1..255"):
        eo.EvidentialOcTree(0.2, 0)
    with pytest.raises(ValueError, match="dempster"):
        eo.EvidentialOcTree(0.2, 3, eo.SemanticConfig(rule="bayes"))
    with pytest.raises(TypeError, match="no parameter 'lenght_scale'"):
        eo.SemanticConfig(lenght_scale=0.3)
    tree, _ = wall_tree()
    with pytest.raises(RuntimeError, match="cannot change the fusion rule"):
        tree.set_config(eo.SemanticConfig(rule="sbki"))


def test_config_keywords_reach_the_map():
    tree, _ = wall_tree(rule="sbki", length_scale=0.4)
    assert tree.rule == "sbki" and tree.config.length_scale == 0.4
    assert eo.SemanticConfig().rule == "dempster"


def test_ot_file_round_trip_is_exact(tmp_path):
    tree, points = wall_tree()
    path = tmp_path / "wall.ot"
    tree.save(str(path))
    loaded = eo.load(path)
    assert loaded.class_names == ["ground", "obstacle", "vegetation"]
    assert loaded.num_leaves == tree.num_leaves and loaded.resolution == tree.resolution
    a, b = tree.query(points), loaded.query(points)
    np.testing.assert_array_equal(a.belief, b.belief)
    np.testing.assert_array_equal(a.occupied, b.occupied)
    assert loaded.to_bytes() == tree.to_bytes()


def test_pickle_and_copy_keep_the_map():
    tree, points = wall_tree()
    for clone in (pickle.loads(pickle.dumps(tree)), tree.copy()):
        assert clone.to_bytes() == tree.to_bytes()
        np.testing.assert_array_equal(clone.query(points).belief, tree.query(points).belief)


def test_missing_and_foreign_files_raise_with_the_path(tmp_path):
    with pytest.raises(RuntimeError, match="cannot open .*missing.ot"):
        eo.load(tmp_path / "missing.ot")
    tree, _ = wall_tree()
    occupancy_only = tmp_path / "wall.bt"
    tree.save_occupancy(str(occupancy_only))
    with pytest.raises(RuntimeError, match="wall.bt is not a readable OctoMap .ot file"):
        eo.load(occupancy_only)
    truncated = tmp_path / "truncated.ot"
    tree.save(str(truncated))
    truncated.write_bytes(truncated.read_bytes()[:-100])
    with pytest.raises(RuntimeError, match="truncated.ot"):
        eo.load(truncated)


def test_color_octree_uses_the_class_table(kitti_classes):
    tree = eo.EvidentialOcTree(0.2, kitti_classes)
    points, evidence = wall(num_classes=kitti_classes.num_classes, label=1)  # car
    tree.insert_scan(points, evidence, origin=ORIGIN)
    colored = tree.to_color_octree(kitti_classes)
    assert tree.to_color_octree(kitti_classes, "vacuity").num_leaves == colored.num_leaves
    assert colored.num_leaves == tree.num_leaves
    assert (colored.colors(points) == kitti_classes.colors[1]).all()
    with pytest.raises(ValueError, match="'class', 'uncertainty'"):
        tree.to_color_octree(kitti_classes, "rainbow")
    with pytest.raises(ValueError, match="class table has 20 classes, the map 3"):
        wall_tree()[0].to_color_octree(kitti_classes)


def test_class_table_matches_the_yaml(kitti_classes):
    assert kitti_classes.num_classes == 20 and kitti_classes.names[1] == "car"
    assert kitti_classes.colors.shape == (20, 3) and list(kitti_classes.colors[1]) == [100, 150, 245]
    raw = np.array([10, 252, 1, 10 | (7 << 16)], dtype=np.uint32)  # car, moving-car, outlier
    np.testing.assert_array_equal(kitti_classes.classes_of_raw(raw), [1, 1, 0, 1])
    with pytest.raises(IndexError, match="9999"):
        kitti_classes.classes_of_raw(np.array([9999], dtype=np.uint32))
    assert eo.bundled_class_table("semantickitti").names == kitti_classes.names


def test_type_stubs_are_installed():
    from pathlib import Path

    package = Path(eo.__file__).parent
    stub = (package / "_core.pyi").read_text()
    assert "def insert_scan(" in stub and "def query(" in stub and "class EvidentialOcTree" in stub
    assert (package / "py.typed").exists()


@pytest.mark.parametrize("attribute, value", [
    ("prob_hit", 1.0), ("prob_hit", float("nan")), ("prob_miss", 0.0),
    ("clamping_thres_min", 0.0), ("clamping_thres_max", 1.0), ("occupancy_thres", 1.0),
])
def test_unsavable_sensor_model_is_refused_by_the_next_insert_with_the_save_reason(
        tmp_path, attribute, value):
    """OctoMap's setters are unchecked: the insert that would use the value refuses it with the
    reason save gives, and the map stays as it was."""
    tree, points = wall_tree()
    before = tree.leaves()
    setattr(tree, attribute, value)
    path = tmp_path / "map.ot"
    with pytest.raises(RuntimeError) as saved:
        tree.save(str(path))
    _, evidence = wall()
    with pytest.raises(ValueError) as inserted:
        tree.insert_scan(points, evidence, origin=ORIGIN)
    assert str(saved.value) == f"cannot save {path}: {inserted.value}"
    assert str(inserted.value).startswith("sensor model: ")
    after = tree.leaves()
    np.testing.assert_array_equal(after.centers, before.centers)
    np.testing.assert_array_equal(after.occupancy, before.occupancy)
    np.testing.assert_array_equal(after.belief, before.belief)
    assert not path.exists()


def test_read_calibration_reads_a_cap_only_file(tmp_path):
    path = tmp_path / "calibration.yaml"
    path.write_text("# fitted by evidential_octomap calibrate\nevidence_cap: 6.25\n")
    calibration = eo.read_calibration(str(path))
    assert (calibration.version, calibration.evidence_cap) == (1, 6.25)
    assert calibration.error_model_terms == []
    tree = eo.EvidentialOcTree(0.2, 3)
    tree.apply_calibration(calibration)
    assert tree.config.evidence_cap == 6.25 and not tree.calibrated


def _calibration_file(tmp_path, classes, weights=(0.5, 2.0)):
    path = tmp_path / "calibration.yaml"
    path.write_text("calibration_version: 2\ncalibration_rule: dempster\n"
                    f"calibration_classes: [{', '.join(classes)}]\nevidence_cap: -1\n"
                    "error_model_terms: [intercept, vacuity]\n"
                    f"error_model_weights: [{weights[0]}, {weights[1]}]\n")
    return str(path)


def test_an_applied_error_model_is_the_maps_error_probability(tmp_path):
    tree = eo.EvidentialOcTree(0.2, ["road", "grass", "tree"])
    points = np.array([[1.0, 0.0, 0.0], [1.0, 1.0, 0.0]], dtype=np.float32)
    evidence = np.array([[6.0, 1.0, 0.0], [0.5, 0.4, 0.3]], dtype=np.float32)
    tree.insert_scan(points, evidence, origin=(0.0, 0.0, 0.0))
    tree.apply_calibration(eo.read_calibration(_calibration_file(tmp_path, tree.class_names)))
    assert tree.calibrated
    answer = tree.query(points)
    # The file's model, written out: P(wrong) = sigmoid(0.5 + 2 ln u).
    expected = 1.0 / (1.0 + np.exp(-(0.5 + 2.0 * np.log(answer.uncertainty))))
    np.testing.assert_allclose(answer.error_probability, expected, rtol=1e-5)
    assert answer.error_probability[0] < answer.error_probability[1]


def test_a_calibration_of_other_classes_is_refused(tmp_path):
    tree = eo.EvidentialOcTree(0.2, ["road", "grass", "tree"])
    path = _calibration_file(tmp_path, ["road", "grass", "water"])
    with pytest.raises(RuntimeError, match="water"):
        tree.apply_calibration(eo.read_calibration(path))
    assert not tree.calibrated


def test_read_calibration_refuses_a_bad_file_with_its_line(tmp_path):
    path = tmp_path / "calibration.yaml"
    path.write_text("evidence_cap: -2\n")
    with pytest.raises(RuntimeError, match="calibration.yaml:1: evidence_cap must be"):
        eo.read_calibration(str(path))
    with pytest.raises(RuntimeError, match="cannot read"):
        eo.read_calibration(str(tmp_path / "missing.yaml"))


def test_the_adaptive_cap_follows_the_inserted_evidence():
    tree = eo.EvidentialOcTree(0.2, 3)
    assert tree.effective_evidence_cap == 3.0  # before any evidence
    points = np.array([[2.0, 0.0, 0.0], [2.0, 0.4, 0.0], [2.0, -0.4, 0.0], [2.0, 0.8, 0.0]])
    evidence = np.zeros((4, 3), np.float32)
    evidence[:, 1] = 30.0
    tree.insert_scan(points, evidence, origin=ORIGIN)
    m = np.log1p(30.0 / 3)
    assert tree.mean_point_log_evidence == pytest.approx(m)
    assert tree.effective_evidence_cap == pytest.approx(2.71 * m ** 0.55)
