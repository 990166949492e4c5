"""`bag map` on ROS 2 bags it did not write: made here with rosbags' own Writer and
serializer (not `bag write`), with other frame names (odom, base_footprint, os_sensor), no
/evidence_source and no /clock. Such a bag maps to the Python API's map of the same scans; a bag
without TF, a map frame the TF does not have and several cloud topics stop with what to fix."""
import subprocess
import sys

import numpy as np
import pytest

pytest.importorskip("rosbags", reason="the bags extra: pip install '.[bags]'")

from rosbags.rosbag2 import StoragePlugin, Writer  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

import evidential_octomap as eo  # noqa: E402
from evidential_octomap import bag  # noqa: E402
from evidential_octomap.tf_buffer import quaternion  # noqa: E402
from bag_helpers import assert_same_map, compare_leaves, tf_exact_dataset  # noqa: E402
from conftest import KITTI, REPO  # noqa: E402

SCANS = 2
CLASSES = REPO / "config" / "classes_semantickitti.yaml"
TS = get_typestore(Stores.ROS2_HUMBLE)
T = TS.types
BASE_TO_SENSOR = np.array([0.25, 0.0, 1.5])  # a mounting other than bag write's


def stamp(ns):
    return T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)


def cloud(ns, frame, points, evidence):
    """PointCloud2 with x, y, z and one float32 `evidence` field of count C, packed here."""
    C = evidence.shape[1]
    rows = np.empty(len(points), dtype=[("xyz", "<f4", 3), ("evidence", "<f4", C)])
    rows["xyz"], rows["evidence"] = points, evidence
    field = T["sensor_msgs/msg/PointField"]
    fields = [field(name="x", offset=0, datatype=7, count=1),
              field(name="y", offset=4, datatype=7, count=1),
              field(name="z", offset=8, datatype=7, count=1),
              field(name="evidence", offset=12, datatype=7, count=C)]
    return T["sensor_msgs/msg/PointCloud2"](
        header=T["std_msgs/msg/Header"](stamp=stamp(ns), frame_id=frame), height=1,
        width=len(points), fields=fields, is_bigendian=False, point_step=rows.itemsize,
        row_step=rows.itemsize * len(points), data=rows.view(np.uint8).reshape(-1),
        is_dense=True)


def tf_message(ns, parent, child, M):
    q = quaternion(M[:3, :3])
    x, y, z = (float(v) for v in M[:3, 3])
    transform = T["geometry_msgs/msg/Transform"](
        translation=T["geometry_msgs/msg/Vector3"](x=x, y=y, z=z),
        rotation=T["geometry_msgs/msg/Quaternion"](x=q[0], y=q[1], z=q[2], w=q[3]))
    return T["tf2_msgs/msg/TFMessage"](transforms=[T["geometry_msgs/msg/TransformStamped"](
        header=T["std_msgs/msg/Header"](stamp=stamp(ns), frame_id=parent), child_frame_id=child,
        transform=transform)])


def write_foreign(path, dataset, with_tf=True, second_cloud_topic=False):
    """A ROS 2 MCAP bag as another team's recorder would leave it."""
    T_base_sensor = np.eye(4)
    T_base_sensor[:3, 3] = BASE_TO_SENSOR
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        add = lambda topic, msgtype: w.add_connection(topic, msgtype, typestore=TS)  # noqa: E731
        points_conn = add("/ouster/points", "sensor_msgs/msg/PointCloud2")
        other_conn = add("/ouster/points_filtered", "sensor_msgs/msg/PointCloud2") \
            if second_cloud_topic else None
        tf_conn = add("/tf", "tf2_msgs/msg/TFMessage") if with_tf else None
        static_conn = add("/tf_static", "tf2_msgs/msg/TFMessage") if with_tf else None
        t0 = 5 * 10**9
        if with_tf:
            w.write(static_conn, t0, TS.serialize_cdr(
                tf_message(t0, "base_footprint", "os_sensor", T_base_sensor),
                "tf2_msgs/msg/TFMessage"))
        for i in range(SCANS):
            scan, ns = dataset.load(i), t0 + i * 100_000_000
            if with_tf:
                T_odom_base = scan.pose @ np.linalg.inv(T_base_sensor)
                w.write(tf_conn, ns, TS.serialize_cdr(
                    tf_message(ns, "odom", "base_footprint", T_odom_base),
                    "tf2_msgs/msg/TFMessage"))
            data = TS.serialize_cdr(cloud(ns, "os_sensor", scan.points,
                                          eo.derive_evidence(scan, 20)),
                                    "sensor_msgs/msg/PointCloud2")
            w.write(points_conn, ns, data)
            if other_conn is not None:
                w.write(other_conn, ns, data)
    return path


@pytest.fixture(scope="module")
def exact(tmp_path_factory, kitti_classes):
    path = tf_exact_dataset(KITTI, tmp_path_factory.mktemp("exact"), kitti_classes, SCANS)
    return eo.Dataset.open(str(path), kitti_classes)


@pytest.fixture(scope="module")
def foreign(tmp_path_factory, exact):
    return write_foreign(tmp_path_factory.mktemp("foreign") / "run", exact)


def test_a_foreign_bag_maps_to_the_python_api_map_of_the_same_scans(foreign, exact,
                                                                    kitti_classes):
    result = bag.map_bag(foreign, kitti_classes, bag.MapOptions(frame="odom"))
    s = result.summary
    assert (s["topic"], s["scans_mapped"], s["dropped"]) == ("/ouster/points", SCANS, [])
    assert s["evidence_declared"] is None
    assert s["tf"]["frames"] == ["base_footprint", "odom", "os_sensor"]
    direct = eo.EvidentialOcTree(0.2, kitti_classes)
    for i in range(SCANS):
        scan = exact.load(i)
        direct.insert_scan(scan.points_world(), eo.derive_evidence(scan, 20), origin=scan.origin)
    assert_same_map(compare_leaves(direct.leaves(), result.tree.leaves()))


def test_a_map_frame_the_tf_lacks_is_refused_naming_the_frames(foreign, kitti_classes):
    with pytest.raises(ValueError, match=r"the map frame 'map' is not in the bag's TF \(frames: "
                                         r"base_footprint, odom, os_sensor\): choose one of "
                                         r"them with --frame"):
        bag.map_bag(foreign, kitti_classes, bag.MapOptions(frame="map"))


def test_a_bag_without_tf_is_refused_naming_the_clouds_frame(tmp_path, exact, kitti_classes):
    path = write_foreign(tmp_path / "no_tf", exact, with_tf=False)
    run = subprocess.run(
        [sys.executable, "-m", "evidential_octomap.bag", "map", str(path), "--classes",
         str(CLASSES), "--out", str(tmp_path / "out"), "-q"], capture_output=True, text=True)
    assert run.returncode == 1, run.stdout + run.stderr
    assert "Traceback" not in run.stderr
    assert ("the bag has no TF (no tf2_msgs/TFMessage on /tf or /tf_static), so the clouds' "
            "frame 'os_sensor' cannot be placed in the map frame 'map'") in run.stderr
    # the clouds' own frame needs no TF
    result = bag.map_bag(path, kitti_classes, bag.MapOptions(frame="os_sensor"))
    assert result.summary["scans_mapped"] == SCANS


def test_several_cloud_topics_ask_which_one(tmp_path, exact, kitti_classes):
    path = write_foreign(tmp_path / "two", exact, second_cloud_topic=True)
    with pytest.raises(ValueError, match=r"2 PointCloud2 topics \(/ouster/points \(2\), "
                                         r"/ouster/points_filtered \(2\)\): which one should be "
                                         r"mapped\? Choose it with --topic"):
        bag.map_bag(path, kitti_classes, bag.MapOptions(frame="odom"))
    result = bag.map_bag(path, kitti_classes,
                         bag.MapOptions(frame="odom", topic="/ouster/points_filtered"))
    assert result.summary["scans_mapped"] == SCANS
