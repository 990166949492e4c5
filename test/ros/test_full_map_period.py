#!/usr/bin/python3
"""rostest of ~full_map_period: with a period far longer than the test, every scan refreshes the
views (semantic markers) but the whole-map output (evidential_map) is sent once, after the first
scan, until a forced publish (~reset) sends it again; a late subscriber gets the latest views
and the latched whole map; ~status carries the publish times."""
import os
import sys
import unittest

import numpy as np
import rospkg
import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import TransformStamped
from evidential_octomap.msg import EvidentialMap, MappingStatus
from sensor_msgs.msg import PointCloud2
from std_msgs.msg import Header
from std_srvs.srv import Empty
from visualization_msgs.msg import MarkerArray

sys.path.insert(0, os.path.dirname(__file__))
from topic_store import TopicStore  # noqa: E402

ROOT = rospkg.RosPack().get_path("evidential_octomap")
sys.path.insert(0, os.path.join(ROOT, "src", "ros", "scripts"))
from play_semantickitti import make_cloud  # noqa: E402

NODE = "/evidential_mapping_node"
CLASSES = 20
BUILDING = 13


def wall_cloud(x):
    """A 2 m x 2 m building wall at x (sensor frame), one-hot evidence."""
    y, z = np.meshgrid(np.arange(-1.0, 1.0, 0.05), np.arange(0.0, 2.0, 0.05))
    xyz = np.column_stack([np.full(y.size, x), y.ravel(), z.ravel()]).astype(np.float32)
    evidence = np.zeros((len(xyz), CLASSES), np.float32)
    evidence[:, BUILDING] = 20.0
    return make_cloud(xyz, evidence, Header(stamp=rospy.Time.now(), frame_id="lidar"))


def cubes(markers):
    return sum(len(m.points) for m in markers.markers)


class FullMapPeriodTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_full_map_period")
        cls.topics = TopicStore()
        cls.topics.subscribe("/evidential_map", EvidentialMap)
        cls.topics.subscribe("/occupied_cells_vis_array", MarkerArray)
        cls.topics.subscribe(NODE + "/status", MappingStatus, queue_size=50)
        cls.clouds = rospy.Publisher("/cloud_in", PointCloud2, queue_size=5)
        cls.tf = tf2_ros.StaticTransformBroadcaster()
        lidar = TransformStamped()
        lidar.header.frame_id, lidar.child_frame_id = "map", "lidar"
        lidar.transform.translation.x, lidar.transform.rotation.w = 1.0, 1.0
        cls.tf.sendTransform(lidar)
        rospy.wait_for_service(NODE + "/query", timeout=60)
        deadline = rospy.Time.now() + rospy.Duration(30)
        while cls.clouds.get_num_connections() == 0 and rospy.Time.now() < deadline:
            rospy.sleep(0.05)

    def insert(self, cloud, n):
        """Publishes `cloud` until the node has inserted n clouds (ROS 1 transport has been seen
        to lose a message around a new connection); the first such ~status, None if never."""
        for _ in range(3):
            self.clouds.publish(cloud)
            status = self.inserted(n, timeout_s=20)
            if status is not None:
                return status
        return None

    def inserted(self, n, timeout_s=60):
        """The first ~status with n clouds inserted (None after the hang guard)."""
        deadline = rospy.Time.now() + rospy.Duration(timeout_s)
        while rospy.Time.now() < deadline:
            done = [s for s in self.topics.wait_for(NODE + "/status") or []
                    if s.clouds_inserted >= n]
            if done:
                return done[0]
            rospy.sleep(0.05)
        return None

    def test_views_follow_every_scan_and_the_full_map_waits_for_its_period(self):
        self.assertIsNotNone(self.insert(wall_cloud(4.0), 1))
        first = self.topics.wait_for("/evidential_map", 1)
        self.assertIsNotNone(first, "the first scan's whole map was not sent")
        views = self.topics.wait_for("/occupied_cells_vis_array", 1)
        shown = cubes(views[-1])
        self.assertGreater(shown, 0)

        self.assertIsNotNone(self.insert(wall_cloud(7.0), 2))  # a second wall: more voxels
        grown = None
        deadline = rospy.Time.now() + rospy.Duration(30)
        while grown is None and rospy.Time.now() < deadline:
            latest = self.topics.wait_for("/occupied_cells_vis_array", 1)[-1]
            grown = latest if cubes(latest) > shown else None
            rospy.sleep(0.05)
        self.assertIsNotNone(grown, "the views did not follow the second scan")
        rospy.sleep(2.0)  # the 1 Hz pass runs at least once; the map is still within its period
        self.assertEqual(len(self.topics.wait_for("/evidential_map", 1)), 1)

        # A subscriber that comes late gets the views the live one has now and the latched
        # whole map of the first scan.
        late = TopicStore()
        late.subscribe("/occupied_cells_vis_array", MarkerArray)
        late.subscribe("/evidential_map", EvidentialMap)
        late_views = late.wait_for("/occupied_cells_vis_array", 1, timeout_s=30)
        self.assertIsNotNone(late_views, "a late subscriber got no views")
        live_views = self.topics.wait_for("/occupied_cells_vis_array", 1)[-1]
        self.assertEqual(cubes(late_views[0]), cubes(live_views))
        self.assertGreater(cubes(late_views[0]), shown)
        late_map = late.wait_for("/evidential_map", 1, timeout_s=30)
        self.assertIsNotNone(late_map, "a late subscriber got no whole map")
        self.assertEqual(late_map[0].header.stamp, first[0].header.stamp)
        self.assertEqual(late_map[0].data, first[0].data)

        status = self.topics.wait_for(NODE + "/status")[-1]
        self.assertGreater(status.last_views_ms, 0.0, status)
        self.assertGreater(status.last_full_maps_ms, 0.0, status)
        self.assertGreaterEqual(status.max_publish_ms, status.last_publish_ms, status)

        rospy.ServiceProxy(NODE + "/reset", Empty)()  # a forced publish sends the whole map
        self.assertIsNotNone(self.topics.wait_for("/evidential_map", 2, timeout_s=30),
                             "a forced publish did not send the whole map")


if __name__ == "__main__":
    rostest.rosrun("evidential_octomap", "full_map_period", FullMapPeriodTest)
