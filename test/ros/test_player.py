#!/usr/bin/python3
"""rostest of play_semantickitti.py: the cloud layout, the one-hot derived evidence against the
bundled files, the map -> velodyne pose formula, and the latched evidence_source."""
import os
import unittest

import numpy as np
import rospkg
import rospy
import rostest
import yaml
from sensor_msgs.msg import PointCloud2
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage
from topic_store import TopicStore

PKG = "evidential_octomap"


class PlayerTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_player")
        root = rospkg.RosPack().get_path(PKG)
        cls.data = os.path.join(root, "data", "semantickitti_08_first10")
        with open(os.path.join(root, "config", "classes_semantickitti.yaml")) as f:
            table = yaml.safe_load(f)
        cls.num_classes = len(table["classes"])
        cls.learning_map = {int(k): int(v) for k, v in table["learning_map"].items()}
        cls.topics = TopicStore()
        cls.topics.subscribe("/velodyne_points", PointCloud2)
        cls.topics.subscribe("/tf", TFMessage, queue_size=20)
        cls.topics.subscribe("/play_semantickitti/evidence_source", String)

    def wait_for(self, topic):
        messages = self.topics.wait_for(topic)
        self.assertIsNotNone(messages, "nothing on " + topic)
        return messages

    def test_cloud_has_xyz_and_one_hot_derived_evidence_of_the_predictions(self):
        cloud = self.wait_for("/velodyne_points")[0]
        self.assertEqual(cloud.header.frame_id, "velodyne")
        fields = {f.name: f for f in cloud.fields}
        self.assertEqual(fields["evidence"].count, self.num_classes)
        dtype = np.dtype({"names": ["x", "y", "z", "evidence"],
                          "formats": ["<f4", "<f4", "<f4", ("<f4", (self.num_classes,))],
                          "offsets": [fields[n].offset for n in ("x", "y", "z", "evidence")],
                          "itemsize": cloud.point_step})
        points = np.frombuffer(bytes(cloud.data), dtype=dtype, count=cloud.width)
        # Which bundled scan is it? Match the point count, then compare with the files.
        scans = {}
        for name in ("000008", "000009"):
            xyz = np.fromfile(os.path.join(self.data, "velodyne", name + ".bin"), "<f4").reshape(-1, 4)
            scans[xyz.shape[0]] = (name, xyz)
        self.assertIn(cloud.width, scans)
        name, xyz = scans[cloud.width]
        np.testing.assert_array_equal(points["x"], xyz[:, 0])
        np.testing.assert_array_equal(points["z"], xyz[:, 2])
        raw = np.fromfile(os.path.join(self.data, "predictions", name + ".label"), "<u4") & 0xFFFF
        expected = np.array([self.learning_map[int(r)] for r in raw])
        ev = points["evidence"]
        np.testing.assert_array_equal(np.argmax(ev, axis=1)[expected > 0], expected[expected > 0])
        np.testing.assert_array_equal(np.count_nonzero(ev, axis=1), 1)  # one-hot
        np.testing.assert_array_equal(ev.max(axis=1), 20.0)               # magnitude 20

    def test_velodyne_pose_is_inv_tr_times_p_times_tr(self):
        tfs = self.wait_for("/tf")
        t = tfs[0].transforms[0]
        self.assertEqual((t.header.frame_id, t.child_frame_id), ("map", "velodyne"))
        calib = dict(line.split(":", 1) for line in open(os.path.join(self.data, "calib.txt")) if ":" in line)
        tr = np.eye(4)
        tr[:3, :4] = np.array(calib["Tr"].split(), float).reshape(3, 4)
        poses = [np.array(l.split(), float).reshape(3, 4) for l in open(os.path.join(self.data, "poses.txt"))]
        candidates = []
        for i in (8, 9):
            p = np.eye(4)
            p[:3, :4] = poses[i]
            candidates.append((np.linalg.inv(tr) @ p @ tr)[:3, 3])
        got = np.array([t.transform.translation.x, t.transform.translation.y, t.transform.translation.z])
        self.assertLess(min(np.linalg.norm(got - c) for c in candidates), 1e-6)
        self.assertGreater(got[0], 4.0)  # the car drove forward along velodyne x
        q = t.transform.rotation
        self.assertAlmostEqual(q.x ** 2 + q.y ** 2 + q.z ** 2 + q.w ** 2, 1.0, places=6)

    def test_evidence_source_says_derived(self):
        source = self.wait_for("/play_semantickitti/evidence_source")[0].data
        self.assertTrue(source.startswith("derived"), source)
        self.assertIn("magnitude 20", source)


if __name__ == "__main__":
    rostest.rosrun(PKG, "player", PlayerTest)
