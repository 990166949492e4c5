#!/usr/bin/python3
"""rostest: what a user runs beside the node works with the packages the scripts install.
A tf2 Python client (python3-tf2-ros), std_srvs/Empty from Python and from `rosservice call`
(python3-std-srvs), the node's own services and ~status from the command-line tools."""
import subprocess
import unittest

import rospy
import rostest
import std_srvs.srv
import tf2_ros
from geometry_msgs.msg import TransformStamped

NODE = "/evidential_mapping_node"


def run(*args):
    """Runs a ROS command-line tool; returns (exit code, stdout + stderr)."""
    done = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          timeout=60)
    return done.returncode, done.stdout


class UserToolsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_user_tools")
        rospy.wait_for_service(NODE + "/reset", timeout=60)

    def test_tf2_python_client_looks_up_a_transform(self):
        broadcaster = tf2_ros.StaticTransformBroadcaster()
        t = TransformStamped()
        t.header.stamp = rospy.Time.now()
        t.header.frame_id = "map"
        t.child_frame_id = "lidar"
        t.transform.translation.x = 1.5
        t.transform.rotation.w = 1.0
        broadcaster.sendTransform(t)
        buffer = tf2_ros.Buffer()
        tf2_ros.TransformListener(buffer)
        found = buffer.lookup_transform("map", "lidar", rospy.Time(0), rospy.Duration(30))
        self.assertAlmostEqual(found.transform.translation.x, 1.5)

    def test_reset_from_python_with_std_srvs(self):
        reset = rospy.ServiceProxy(NODE + "/reset", std_srvs.srv.Empty)
        reset()  # raises when the type cannot be loaded or the call fails

    def test_rosservice_call_reset_and_query(self):
        code, out = run("rosservice", "call", NODE + "/reset")
        self.assertEqual(code, 0, out)
        code, out = run("rosservice", "call", NODE + "/query", "points: [{x: 0, y: 0, z: 0}]")
        self.assertEqual(code, 0, out)
        self.assertIn("labels: [-1]", out)

    def test_rostopic_echo_status(self):
        code, out = run("rostopic", "echo", "-n1", NODE + "/status")
        self.assertEqual(code, 0, out)
        self.assertIn("clouds_received:", out)


if __name__ == "__main__":
    rostest.rosrun("evidential_octomap", "user_tools", UserToolsTest)
