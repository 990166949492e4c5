#!/usr/bin/python3
"""rostest of play_semantickitti.py with ~evidence learned: the evidence of scan 000000 comes from
the C++ learned head (cross-fitted fold B), so its argmax accuracy equals what the training script
computed for that scan (test/fixtures/learned_evidence_points.txt), u varies from point to point,
and ~evidence_source says "learned (cross-fitted)"."""
import os
import unittest

import numpy as np
import rospkg
import rospy
import rostest
import yaml
from sensor_msgs.msg import PointCloud2
from std_msgs.msg import String
from topic_store import TopicStore

PKG = "evidential_octomap"


class PlayerLearnedTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_player_learned")
        cls.root = rospkg.RosPack().get_path(PKG)
        with open(os.path.join(cls.root, "config", "classes_semantickitti.yaml")) as f:
            table = yaml.safe_load(f)
        cls.num_classes = len(table["classes"])
        cls.lut = np.zeros(1 << 16, np.int64)
        for raw, c in table["learning_map"].items():
            cls.lut[int(raw)] = int(c)
        cls.topics = TopicStore()
        cls.topics.subscribe("/velodyne_points", PointCloud2, queue_size=2)
        cls.topics.subscribe("/play_semantickitti/evidence_source", String)

    def first(self, topic):
        messages = self.topics.wait_for(topic, timeout_s=90)
        self.assertIsNotNone(messages, "nothing on " + topic)
        return messages[0]

    def script_accuracy(self):
        path = os.path.join(self.root, "test", "fixtures", "learned_evidence_points.txt")
        for line in open(path):
            w = line.split()
            if w[:4] == ["scan", "000000", "fold", "B"]:
                return float(w[5])
        self.fail("no accuracy of scan 000000 in " + path)

    def test_evidence_is_the_cross_fitted_learned_head(self):
        cloud = self.first("/velodyne_points")
        fields = {f.name: f for f in cloud.fields}
        self.assertEqual(fields["evidence"].count, self.num_classes)
        dtype = np.dtype({"names": ["evidence"], "formats": [("<f4", (self.num_classes,))],
                          "offsets": [fields["evidence"].offset], "itemsize": cloud.point_step})
        ev = np.frombuffer(bytes(cloud.data), dtype=dtype, count=cloud.width)["evidence"]
        data = os.path.join(self.root, "data", "semantickitti_08_first10")
        xyz = np.fromfile(os.path.join(data, "velodyne", "000000.bin"), "<f4").reshape(-1, 4)
        self.assertEqual(cloud.width, xyz.shape[0])
        self.assertTrue(np.isfinite(ev).all() and (ev >= 0).all())
        gt = self.lut[np.fromfile(os.path.join(data, "labels", "000000.label"), "<u4") & 0xFFFF]
        has_return = np.any(xyz[:, :3] != 0, axis=1)
        keep = (gt > 0) & has_return
        accuracy = (ev.argmax(axis=1)[keep] == gt[keep]).mean()
        self.assertAlmostEqual(accuracy, self.script_accuracy(), delta=1e-3)
        u = self.num_classes / (ev.sum(axis=1) + self.num_classes)
        self.assertGreater(u[keep].std(), 0.05)  # not a constant like derived one-hot evidence

    def test_evidence_source_says_learned_cross_fitted(self):
        source = self.first("/play_semantickitti/evidence_source").data
        self.assertTrue(source.startswith("learned (cross-fitted)"), source)


if __name__ == "__main__":
    rostest.rosrun(PKG, "player_learned", PlayerLearnedTest)
