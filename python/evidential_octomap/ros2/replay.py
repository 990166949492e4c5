"""Publishes a SemanticKITTI-layout directory (the bundled scans) as a ROS 2 robot would: the
evidence cloud, /tf (map -> base_link at each scan) and /tf_static (base_link -> velodyne), with
the frames and stamps `bag write` uses, so the node maps what the CLI and the bag mapper map.

    python -m evidential_octomap.ros2.replay data/semantickitti_08_first10 --rate 10
    python -m evidential_octomap.ros2.replay DATA --paced   # next scan once the node took one

--paced waits for the node's status (clouds inserted + dropped) before the next scan, so a slow
machine still maps every scan in order (the map equals the CLI's); --rate R publishes open loop.
"""
import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from .. import _core, bundled_class_table, pointcloud2
from ..bag import WriteOptions, scan_evidence
from ..tf_buffer import quaternion

import rclpy  # noqa: E402
from geometry_msgs.msg import TransformStamped  # noqa: E402
from sensor_msgs.msg import PointCloud2, PointField  # noqa: E402
from std_msgs.msg import String  # noqa: E402
from tf2_msgs.msg import TFMessage  # noqa: E402

from .node import LATCHED, TF_STATIC_QOS  # noqa: E402


def transform(stamp, parent, child, M):
    t = TransformStamped()
    t.header.stamp, t.header.frame_id, t.child_frame_id = stamp, parent, child
    t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = (
        float(v) for v in M[:3, 3])
    q = quaternion(M[:3, :3])
    (t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z,
     t.transform.rotation.w) = (float(v) for v in q)
    return t


def cloud(stamp, frame, columns):
    rows, step, data = pointcloud2.pack(columns)
    n = len(next(iter(columns.values())))
    msg = PointCloud2(height=1, width=n, is_bigendian=False, point_step=step, row_step=step * n,
                      is_dense=True)
    msg.header.stamp, msg.header.frame_id = stamp, frame
    msg.fields = [PointField(name=a, offset=o, datatype=d, count=c) for a, o, d, c in rows]
    msg.data = data.tobytes()
    return msg


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m evidential_octomap.ros2.replay",
                                description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("data")
    p.add_argument("--classes", default=None, help="class table (default: bundled SemanticKITTI)")
    p.add_argument("--scans", type=int, default=None)
    p.add_argument("--rate", type=float, default=10.0, help="scans per second (default 10)")
    p.add_argument("--paced", action="store_true", help="wait for the node after each scan")
    p.add_argument("--loops", type=int, default=1,
                   help="play the scans this many times (stamps go on; a benchmark)")
    p.add_argument("--status", default="/evidential_mapping_node/status")
    p.add_argument("--topic", default="/velodyne_points/evidence")
    p.add_argument("--raw", action="store_true",
                   help="publish the raw clouds (x, y, z, intensity) instead of the evidence ones")
    p.add_argument("--no-tf-after", type=int, default=None, metavar="K",
                   help="publish no /tf from scan K on (those clouds have no transform)")
    p.add_argument("--malformed-first", action="store_true",
                   help="first publish one cloud whose evidence field has the wrong count")
    args = p.parse_args(rclpy.utilities.remove_ros_args(sys.argv if argv is None else argv)[1:])
    classes = (_core.ClassTable.load(args.classes) if args.classes
               else bundled_class_table("semantickitti"))
    dataset = _core.Dataset.open(args.data, classes)
    n = len(dataset) if args.scans is None else min(args.scans, len(dataset))
    options = WriteOptions()
    # Fast DDS's writers repair a lost sample at their next heartbeat, 3 s by default; a /tf
    # lost beside large clouds then came too late for them (fastdds_replay.xml). A profile of
    # the user's own is kept.
    if not any(os.environ.get(f"FAST{v}_DEFAULT_PROFILES_FILE") for v in ("DDS", "RTPS")):
        os.environ["FASTDDS_DEFAULT_PROFILES_FILE"] = str(
            Path(__file__).with_name("fastdds_replay.xml"))
    rclpy.init(args=sys.argv if argv is None else argv)
    node = rclpy.create_node("evidential_octomap_replay")
    # reliable, keeping 10: a reader slower than the rate still gets each cloud of a burst
    pub = node.create_publisher(PointCloud2, args.topic, 10)
    tf_pub = node.create_publisher(TFMessage, "/tf", 100)
    static_pub = node.create_publisher(TFMessage, "/tf_static", TF_STATIC_QOS)
    taken = [0]

    def on_status(msg):
        s = json.loads(msg.data)
        taken[0] = s["clouds_inserted"] + s["clouds_dropped"]
    node.create_subscription(String, args.status, on_status, LATCHED)
    # wait for the node (its cloud_in subscription, then its /tf one, a moment more: the two
    # are matched one by one) before sending anything
    for writer, wait_s in ((pub, 30.0), (tf_pub, 2.0)):
        deadline = time.monotonic() + wait_s
        while writer.get_subscription_count() == 0 and time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.1)
    T_base_sensor = np.eye(4)
    T_base_sensor[:3, 3] = options.base_to_sensor
    start = rclpy.time.Time(nanoseconds=options.start_ns).to_msg()
    static_pub.publish(TFMessage(transforms=[transform(
        start, options.base_frame, options.sensor_frame, T_base_sensor)]))
    sent = 0

    def wait_for_node():
        end = time.monotonic() + 120
        while args.paced and taken[0] < sent and time.monotonic() < end:
            rclpy.spin_once(node, timeout_sec=0.05)

    if args.malformed_first:
        bad = cloud(start, options.sensor_frame, {"x": np.zeros(3, np.float32),
                                                  "y": np.zeros(3, np.float32),
                                                  "z": np.zeros(3, np.float32),
                                                  "evidence": np.ones((3, 2), np.float32)})
        pub.publish(bad)
        sent += 1
        wait_for_node()
    period = 1.0 / args.rate if args.rate > 0 else 0.0
    evidences = {}
    t_next = time.monotonic()
    scans = [dataset.load(i) for i in range(n)]
    for k in range(n * args.loops):
        i, scan = k % n, scans[k % n]
        stamp = rclpy.time.Time(nanoseconds=options.start_ns + k * 100_000_000).to_msg()
        if args.no_tf_after is None or k < args.no_tf_after:
            tf_pub.publish(TFMessage(transforms=[transform(
                stamp, options.world_frame, options.base_frame,
                scan.pose @ np.linalg.inv(T_base_sensor))]))
        columns = {"x": scan.points[:, 0], "y": scan.points[:, 1], "z": scan.points[:, 2]}
        if args.raw:
            columns["intensity"] = scan.remission
        else:
            columns["evidence"] = evidences.setdefault(i, scan_evidence(scan, classes, options))
        pub.publish(cloud(stamp, options.sensor_frame, columns))
        sent += 1
        rclpy.spin_once(node, timeout_sec=0.0)
        wait_for_node()
        t_next += period
        time.sleep(max(0.0, t_next - time.monotonic()))
    wait_for_node()
    # a reliable writer that goes away drops what its readers have not acknowledged yet: the
    # last clouds, and the transforms they wait for
    for writer in (pub, tf_pub):
        writer.wait_for_all_acked(rclpy.duration.Duration(seconds=30))
    print(json.dumps({"sent": sent}), flush=True)
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
