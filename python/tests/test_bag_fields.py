"""PointCloud2 field rules (pointcloud2.py, mirroring src/ros/conversions.cpp) on hand-built
messages: every semantic field form, layouts (padding, byte order, float64, organised clouds with
NaN), and the refusals with their messages."""
from types import SimpleNamespace as Msg

import numpy as np
import pytest

import evidential_octomap as eo
from evidential_octomap import pointcloud2 as pc2
from evidential_octomap.pointcloud2 import FLOAT32, FLOAT64, UINT16, UINT32, CloudError

C = 4


def cloud(columns, order="<", pad=0, height=1):
    """A message of named columns: (name, numpy type, values (N,) or (N, k)); `pad` bytes after
    each point and after each row."""
    n = len(columns[0][2])
    descr = [(name, order + t, () if np.ndim(v) == 1 else (np.shape(v)[1],))
             for name, t, v in columns]
    dtype = np.dtype(descr)
    step = dtype.itemsize + pad
    width = n // height
    data = bytearray()
    rows = np.empty(n, dtype=dtype)
    for name, _, v in columns:
        rows[name] = v
    raw = rows.tobytes()
    for r in range(height):
        for i in range(r * width, (r + 1) * width):
            data += raw[i * dtype.itemsize:(i + 1) * dtype.itemsize] + b"\xee" * pad
        data += b"\xff" * pad  # row padding
    types = {"f4": FLOAT32, "f8": FLOAT64, "u2": UINT16, "u4": UINT32}
    fields = [Msg(name=name, offset=dtype.fields[name][1], datatype=types[t],
                  count=1 if np.ndim(v) == 1 else np.shape(v)[1]) for name, t, v in columns]
    return Msg(height=height, width=width, fields=fields, is_bigendian=order == ">",
               point_step=step, row_step=step * width + pad, data=bytes(data), is_dense=False)


XYZ = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]], dtype=np.float32)
E = np.array([[1, 0, 0, 2], [0, 3, 0, 0], [0, 0, 4, 0]], dtype=np.float32)


def xyz_columns(t="f4"):
    return [("x", t, XYZ[:, 0]), ("y", t, XYZ[:, 1]), ("z", t, XYZ[:, 2])]


def test_an_evidence_field_of_count_c_is_read_as_is():
    got = pc2.decode(cloud(xyz_columns() + [("evidence", "f4", E)]), C)
    np.testing.assert_array_equal(got.points, XYZ)
    np.testing.assert_array_equal(got.evidence, E)
    assert got.source == "evidence[4]" and got.nonfinite_points == 0


def test_per_class_fields_big_endian_float64_and_padding_read_the_same():
    cols = xyz_columns("f8") + [(f"evidence_{c}", "f8", E[:, c]) for c in range(C)]
    got = pc2.decode(cloud(cols, order=">", pad=3), C)
    np.testing.assert_array_equal(got.points, XYZ)
    np.testing.assert_array_equal(got.evidence, E)


def test_alpha_is_evidence_plus_one():
    got = pc2.decode(cloud(xyz_columns() + [("alpha", "f4", E + 1)]), C)
    np.testing.assert_array_equal(got.evidence, E)
    assert got.source == "alpha[4]"


def test_logits_and_probabilities_use_the_cores_conversions():
    z = np.array([[2.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [-1.0, 5.0, 0.0, 1.0]], np.float32)
    got = pc2.decode(cloud(xyz_columns() + [("logits", "f4", z)]), C)
    np.testing.assert_allclose(got.evidence, eo.evidence_from_logits(z), rtol=1e-6)
    assert got.evidence[1].sum() == 0  # uniform: no evidence
    p = np.array([[1, 0, 0, 0], [0.25, 0.25, 0.25, 0.25], [0, 0.5, 0.5, 0]], np.float32)
    got = pc2.decode(cloud(xyz_columns() + [("probabilities", "f4", p)]), C)
    np.testing.assert_allclose(got.evidence[0], [20, 0, 0, 0])  # one-hot: E on its class
    exp = pc2.decode(cloud(xyz_columns() + [("logits", "f4", z)]), C, logit_transform="exp")
    np.testing.assert_allclose(exp.evidence, np.exp(z), rtol=1e-6)


def test_a_label_field_gives_one_hot_evidence_and_raw_ids_go_through_the_learning_map():
    got = pc2.decode(cloud(xyz_columns() + [("label", "u2", np.array([0, 3, 1]))]), C,
                     label_magnitude=7)
    np.testing.assert_array_equal(got.evidence.argmax(1), [0, 3, 1])
    assert got.evidence.sum() == 21 and got.source == "label"
    kitti = eo.bundled_class_table("semantickitti")
    raw = np.array([40, 10, 70], dtype=np.uint32)  # road, car, vegetation
    got = pc2.decode(cloud(xyz_columns() + [("label", "u4", raw)]), 20, raw_label_table=kitti)
    np.testing.assert_array_equal(got.evidence.argmax(1), kitti.classes_of_raw(raw))
    unknown = np.array([40, 10, 12345], dtype=np.uint32)
    with pytest.raises(CloudError, match=r"^point 2: .*12345"):
        pc2.decode(cloud(xyz_columns() + [("label", "u4", unknown)]), 20, raw_label_table=kitti)


def test_evidence_wins_over_label_in_auto_and_an_explicit_input_is_obeyed():
    cols = xyz_columns() + [("label", "u2", np.array([0, 0, 0])), ("evidence", "f4", E)]
    assert pc2.decode(cloud(cols), C).source == "evidence[4]"
    assert pc2.decode(cloud(cols), C, input="label").source == "label"
    none = pc2.decode(cloud(cols), C, input="none")
    assert none.evidence.shape == (3, C) and not none.evidence.any()


def test_nan_points_of_an_organised_cloud_are_dropped_and_counted():
    xyz = np.vstack([XYZ, [[np.nan, 0, 0]]]).astype(np.float32)
    e = np.vstack([E, [[1, 1, 1, 1]]]).astype(np.float32)
    cols = [("x", "f4", xyz[:, 0]), ("y", "f4", xyz[:, 1]), ("z", "f4", xyz[:, 2]),
            ("evidence", "f4", e)]
    got = pc2.decode(cloud(cols, pad=2, height=2), C)
    assert got.nonfinite_points == 1
    np.testing.assert_array_equal(got.points, XYZ)
    np.testing.assert_array_equal(got.evidence, E)


def test_a_cloud_without_semantic_fields_has_no_evidence_and_keeps_its_fields_for_a_model():
    got = pc2.decode(cloud(xyz_columns() + [("intensity", "f4", np.array([0.1, 0.2, 0.3]))]), C)
    assert got.evidence is None and got.source == "none"
    np.testing.assert_allclose(got.fields["intensity"], [0.1, 0.2, 0.3], rtol=1e-6)


@pytest.mark.parametrize("columns, kwargs, message", [
    (xyz_columns()[:2], {}, r"missing field 'z' \(fields: x, y\)"),
    (xyz_columns() + [("evidence", "f4", E[:, :3])], {},
     r"field 'evidence' has count 3, expected C = 4 \(num_classes\)"),
    (xyz_columns() + [(f"evidence_{c}", "f4", E[:, c]) for c in (0, 1, 3)], {},
     r"field 'evidence_2' is missing: per-class fields need evidence_0 .. evidence_3"),
    (xyz_columns() + [("evidence", "f4", E * np.array([1, 1, 1, -1], np.float32))], {},
     r"point 0: evidence of class 3 is -2 \(evidence must be finite and >= 0"),
    (xyz_columns() + [("alpha", "f4", E)], {},
     r"point 0: alpha of class 1 is 0 \(alpha must be finite and >= 1"),
    (xyz_columns() + [("evidence", "f4", np.where(E == 3, np.nan, E).astype(np.float32))], {},
     r"point 1: evidence of class 1 is nan \(evidence must be finite and >= 0"),
    (xyz_columns() + [("evidence", "f8", np.where(E == 4, 1e39, E.astype(np.float64)))], {},
     r"point 2: evidence of class 2 is 1e\+39 \(evidence must be finite and >= 0, within float"),
    (xyz_columns() + [("label", "u2", np.array([0, 4, 1]))], {},
     r"point 1: label 4 is outside \[0, 4\)"),
    (xyz_columns() + [("logits", "f4", np.full((3, C), np.inf, np.float32))], {},
     r"point 0: logit of class 0 is inf \(must be finite\)"),
    (xyz_columns(), {"input": "evidence"}, r"missing field 'evidence' \(float32, count 4\)"),
])
def test_malformed_clouds_are_refused_saying_what_is_wrong(columns, kwargs, message):
    with pytest.raises(CloudError, match=message):
        pc2.decode(cloud(columns), C, **kwargs)


def test_truncated_data_is_refused():
    msg = cloud(xyz_columns() + [("evidence", "f4", E)])
    msg.data = msg.data[:-1]
    with pytest.raises(CloudError, match=r"truncated data: 83 bytes for 3 x 1 points need 84"):
        pc2.decode(msg, C)
