#!/usr/bin/python3
"""rostest: the values of the user's config:= file are the ones the node runs with, over the
live profile that launch/mapping.launch loads before it; the node's start-up report names the
profile and those values (the copy it leaves in ~settings_report)."""
import unittest

import rospy
import rostest
from dynamic_reconfigure.msg import Config
from topic_store import TopicStore

NODE = "/evidential_mapping_node"


class LaunchConfigTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_launch_config")
        cls.topics = TopicStore()
        cls.topics.subscribe(NODE + "/parameter_updates", Config)  # values in use, latched
        rospy.wait_for_service(NODE + "/query", timeout=90)

    def test_values_in_use_are_the_users(self):
        updates = self.topics.wait_for(NODE + "/parameter_updates", timeout_s=30)
        self.assertIsNotNone(updates, "no parameter_updates from the node")
        doubles = {p.name: p.value for p in updates[0].doubles}
        self.assertAlmostEqual(doubles["length_scale"], 0.35)
        self.assertAlmostEqual(doubles["ds_multiplier"], 3.0)

    def test_start_up_report_names_the_profile_and_the_users_values(self):
        text = rospy.get_param(NODE + "/settings_report")  # what the node logged at start-up
        self.assertTrue(text.startswith("settings profile: live"), text)
        for part in ("length_scale 0.35", "ds_multiplier 3", "evidence_floor 0.02",
                     "fast_free_space true"):
            self.assertIn(part, text)

if __name__ == "__main__":
    rostest.rosrun("evidential_octomap", "launch_config", LaunchConfigTest)
