#!/usr/bin/python3
"""rostest of docs/your_robot.md: raw clouds without evidence, with TF, from a bag played with
its clock, reach the map only through segmentation_relay.py, and the map is right where the
bundled scans' ground truth says: most queried points are known and carry their GT class."""
import os
import subprocess
import sys
import tempfile
import time
import unittest

import numpy as np
import rosbag
import rospkg
import rospy
import rostest
from evidential_octomap.msg import MappingStatus
from evidential_octomap.srv import QueryMap
from geometry_msgs.msg import Point
from sensor_msgs.msg import PointCloud2, PointField
from std_msgs.msg import Header
from tf2_msgs.msg import TFMessage

PKG = "evidential_octomap"
ROOT = rospkg.RosPack().get_path(PKG)
sys.path.insert(0, os.path.join(ROOT, "src", "ros", "scripts"))
from play_semantickitti import DatasetReader, load_class_table, make_tf  # noqa: E402

DATA = os.path.join(ROOT, "data", "semantickitti_08_first10")
SCANS = ["000000", "000001", "000002"]
MAX_RANGE = 30.0  # [m] keeps the test short; the map is still 60 m across
T0 = 100.0  # bag start [s]
BASE_TO_VELODYNE = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1.73], [0, 0, 0, 1.0]])
NODE = "/evidential_mapping_node"


def raw_cloud(xyzr, label, header):
    """What a LiDAR driver plus a hard-label segmentation network publish: no evidence field."""
    dtype = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("intensity", "<f4"),
                      ("label", "<u4")])
    data = np.empty(len(xyzr), dtype)
    data["x"], data["y"], data["z"], data["intensity"] = xyzr.T
    data["label"] = label
    fields = [PointField(n, o, t, 1) for n, o, t in
              [("x", 0, PointField.FLOAT32), ("y", 4, PointField.FLOAT32), ("z", 8, PointField.FLOAT32),
               ("intensity", 12, PointField.FLOAT32), ("label", 16, PointField.UINT32)]]
    return PointCloud2(header=header, height=1, width=len(data), fields=fields, is_bigendian=False,
                       point_step=dtype.itemsize, row_step=dtype.itemsize * len(data),
                       is_dense=True, data=data.tobytes())


def write_bag(path, reader):
    """Raw clouds in frame velodyne, /tf map -> odom -> base_link, /tf_static base_link -> velodyne."""
    with rosbag.Bag(path, "w") as bag:
        t0 = rospy.Time.from_sec(T0)
        static = make_tf(BASE_TO_VELODYNE, t0, "base_link", "velodyne")
        latched = {"topic": "/tf_static", "type": TFMessage._type, "md5sum": TFMessage._md5sum,
                   "message_definition": TFMessage._full_text, "latching": "1"}
        bag.write("/tf_static", TFMessage([static]), t0, connection_header=latched)
        for i in range(len(SCANS)):
            stamp = t0 + rospy.Duration(2 * i + 1)
            name, xyz, remission, predicted, pose = reader.load(i)
            assert name == SCANS[i], name
            keep = np.linalg.norm(xyz, axis=1) < MAX_RANGE
            odom_base = pose @ np.linalg.inv(BASE_TO_VELODYNE)
            bag.write("/tf", TFMessage([make_tf(np.eye(4), stamp, "map", "odom"),
                                        make_tf(odom_base, stamp, "odom", "base_link")]), stamp)
            xyzr = np.column_stack([xyz, remission])[keep]
            cloud = raw_cloud(xyzr, predicted[keep], Header(stamp=stamp, frame_id="velodyne"))
            bag.write("/os_cloud_node/points", cloud, stamp)


class YourRobotTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_your_robot")
        classes = os.path.join(ROOT, "config", "classes_semantickitti.yaml")
        cls.names = load_class_table(classes)[0]
        cls.ground_truth = DatasetReader(DATA, classes, "labels")
        cls.relayed, cls.status = [], []
        rospy.Subscriber("/segmentation/points", PointCloud2, cls.relayed.append, queue_size=10)
        rospy.Subscriber(NODE + "/status", MappingStatus, cls.status.append, queue_size=10)
        cls.tmp = tempfile.TemporaryDirectory()
        bag = os.path.join(cls.tmp.name, "raw.bag")
        write_bag(bag, DatasetReader(DATA, classes, "predictions"))
        rospy.wait_for_service(NODE + "/query", timeout=120)
        time.sleep(2.0)  # the relay's subscription
        subprocess.run(["rosbag", "play", "--clock", "--quiet", bag], check=True, timeout=120)
        cls.final = cls.wait_for_inserts(len(SCANS), timeout_s=200)

    @classmethod
    def wait_for_inserts(cls, n, timeout_s):
        """The last ~status once n clouds were inserted (wall time: the bag's clock stops)."""
        deadline = time.time() + timeout_s
        while time.time() < deadline:
            if cls.status and cls.status[-1].clouds_inserted >= n:
                return cls.status[-1]
            time.sleep(0.2)
        return cls.status[-1] if cls.status else None

    def test_every_raw_cloud_is_mapped_through_the_relay(self):
        self.assertIsNotNone(self.final, "no ~status from the mapper")
        self.assertEqual(self.final.clouds_inserted, len(SCANS), self.final)
        self.assertEqual(self.final.clouds_dropped_invalid + self.final.clouds_dropped_tf, 0,
                         self.final.last_error)
        self.assertEqual(len(self.relayed), len(SCANS))
        fields = {f.name: f for f in self.relayed[0].fields}
        self.assertEqual(fields["evidence"].count, len(self.names))
        self.assertEqual(self.relayed[0].header.frame_id, "velodyne")

    def test_map_carries_the_ground_truth_classes_where_the_scans_saw_them(self):
        _, xyz, _, gt, pose = self.ground_truth.load(0)
        keep = (np.linalg.norm(xyz, axis=1) < MAX_RANGE) & (gt > 0)
        pick = np.random.default_rng(0).choice(np.flatnonzero(keep), 3000, replace=False)
        world = (pose @ np.c_[xyz[pick], np.ones(len(pick))].T).T[:, :3]
        query = rospy.ServiceProxy(NODE + "/query", QueryMap)
        answer = query([Point(*p) for p in world])
        labels = np.array(answer.labels)
        known = labels >= 0
        self.assertGreater(known.mean(), 0.8)  # the points land in mapped voxels: TF chain right
        accuracy = (labels[known] == gt[pick][known]).mean()
        self.assertGreater(accuracy, 0.85)  # the relay's learned evidence (0.94 measured), not noise
        u = np.array(answer.uncertainties)[known]
        self.assertTrue(((u > 0) & (u < 1)).all())


if __name__ == "__main__":
    rostest.rosrun(PKG, "your_robot", YourRobotTest)
