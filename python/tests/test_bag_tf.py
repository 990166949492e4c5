"""The TF buffer (tf_buffer.py) against hand-computed poses: interpolation (linear translation,
slerp rotation), chains through static and dynamic transforms in both directions, and the errors
for stamps outside the buffer and unknown frames."""
import math

import numpy as np
import pytest

from evidential_octomap.tf_buffer import TfBuffer, TfError, matrix, quaternion

S = 1_000_000_000  # ns


def rot_z(deg):
    a = math.radians(deg)
    return (0.0, 0.0, math.sin(a / 2), math.cos(a / 2))


def rz(deg):
    a = math.radians(deg)
    return np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])


@pytest.fixture
def tf():
    t = TfBuffer()
    # map -> base_link: from (0, 0, 0) yaw 0 at 10 s to (4, 2, 0) yaw 90 deg at 12 s
    t.add("map", "base_link", 10 * S, (0, 0, 0), rot_z(0))
    t.add("map", "base_link", 12 * S, (4, 2, 0), rot_z(90))
    # base_link -> velodyne: static, 1.5 m up and 0.5 m forward
    t.add("base_link", "velodyne", 0, (0.5, 0, 1.5), rot_z(0), static=True)
    return t


def test_a_stamp_between_two_transforms_interpolates_translation_and_rotation(tf):
    T = tf.lookup("map", "base_link", 11 * S + S // 2)  # 3/4 of the way
    np.testing.assert_allclose(T[:3, 3], [3.0, 1.5, 0.0], atol=1e-12)
    np.testing.assert_allclose(T[:3, :3], rz(67.5), atol=1e-12)  # slerp: 3/4 of 90 deg


def test_a_chain_through_a_static_transform_composes_the_edges(tf):
    T = tf.lookup("map", "velodyne", 11 * S)  # base at (2, 1, 0) yaw 45 deg
    p = T @ np.array([1.0, 0.0, 0.0, 1.0])   # 1 m ahead of the sensor
    # sensor at base + R(45) (0.5, 0, 1.5); the point 1 m further along the 45-degree heading
    h = math.sqrt(0.5)
    np.testing.assert_allclose(p[:3], [2 + 1.5 * h, 1 + 1.5 * h, 1.5], atol=1e-12)


def test_the_inverse_lookup_is_the_inverse_transform(tf):
    T = tf.lookup("map", "velodyne", 11 * S + 123)
    T_inv = tf.lookup("velodyne", "map", 11 * S + 123)
    np.testing.assert_allclose(T @ T_inv, np.eye(4), atol=1e-12)


def test_a_stamp_on_a_sample_returns_it_exactly(tf):
    T = tf.lookup("map", "base_link", 12 * S)
    np.testing.assert_array_equal(T, matrix((4, 2, 0), rot_z(90)))


def test_slerp_takes_the_short_way_round():
    t = TfBuffer()
    t.add("a", "b", 0, (0, 0, 0), rot_z(170))
    q = rot_z(-170)
    t.add("a", "b", 2 * S, (0, 0, 0), tuple(-v for v in q))  # same rotation, other sign
    np.testing.assert_allclose(t.lookup("a", "b", S)[:3, :3], rz(180), atol=1e-12)


def test_quaternion_and_matrix_round_trip():
    R = rz(33) @ np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]])
    np.testing.assert_allclose(matrix((1, 2, 3), quaternion(R))[:3, :3], R, atol=1e-15)


def test_a_stamp_outside_the_buffer_names_the_frames_the_edge_and_the_time_range(tf):
    with pytest.raises(TfError) as e:
        tf.lookup("map", "velodyne", 12 * S + S // 2)
    assert str(e.value) == (
        "cannot transform 'velodyne' to 'map' at 12.500000000 s: the stamp is 0.500 s after the "
        "last transform 'map' -> 'base_link' (2 transforms from 10.000000000 s to 12.000000000 s; "
        "the buffer holds /tf from 10.000000000 s to 12.000000000 s)")
    with pytest.raises(TfError, match=r"2.000 s before the first transform 'map' -> 'base_link'"):
        tf.lookup("map", "velodyne", 8 * S)


def test_unknown_frames_and_separate_trees_are_refused(tf):
    with pytest.raises(TfError, match=r"frame 'odom' is not in the TF buffer \(frames: "
                                      r"base_link, map, velodyne\)"):
        tf.lookup("odom", "velodyne", 11 * S)
    tf.add("world", "camera", 11 * S, (0, 0, 0), rot_z(0))
    with pytest.raises(TfError, match="separate TF trees"):
        tf.lookup("map", "camera", 11 * S)


def test_static_transforms_hold_at_any_time(tf):
    T = tf.lookup("base_link", "velodyne", 10**6 * S)
    np.testing.assert_array_equal(T[:3, 3], [0.5, 0, 1.5])
