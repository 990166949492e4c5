#!/usr/bin/python3
"""rostest: autosave and recovery of evidential_mapping_node, and its saves on full and read-only
filesystems. A real roscore (rostest's), the real node started by this test (rosrun) so that it
can be killed with SIGKILL and started again with the same arguments, real PointCloud2 and TF.

Kill test: scan g is a few points at x = SPACING * g (its own voxel; the sensor stands below
it), published at RATE Hz, each until it is in the map. The node is killed at a random moment, started again, and asked
(~query) which scans its map holds: they must be a prefix 0 .. R-1 of the scans (nothing lost in
the middle), every restart must log that it resumed from the autosave, and the scans lost, from
R to the last one the node had inserted before the kill, must span at most one autosave period
(plus the time a write takes). At the end no temporary may be left beside the autosave.
EVIDENTIAL_AUTOSAVE_KILLS (default 4: CI) sets the number of kills; EVIDENTIAL_AUTOSAVE_REPORT
a file for the per-kill figures (JSON lines).

Disk test (root: a tmpfs mounted by the test; otherwise skipped with the reason): ~save_map and
the autosave into a nearly full and into a read-only filesystem fail with the reason, keep the
previous file byte-identical, leave no temporary, and the node goes on mapping.
"""
import json
import os
import random
import shutil
import signal
import struct
import subprocess
import tempfile
import time
import unittest

import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import Point, TransformStamped
from sensor_msgs.msg import PointCloud2, PointField

from evidential_octomap.msg import MappingStatus
from evidential_octomap.srv import QueryMap, SaveMap

KILLS = int(os.environ.get("EVIDENTIAL_AUTOSAVE_KILLS", "4"))
PERIOD = float(os.environ.get("EVIDENTIAL_AUTOSAVE_PERIOD", "1.0"))
RATE = 20.0      # scans per second
SPACING = 0.6    # m between the scans' voxels
WRITE_SLACK = 0.5  # s: an autosave's serialisation and write, and ~status latency


def cloud(stamp, frame):
    """Four points in one voxel 3 m above the sensor, label 1 (float32 x y z, uint32 label)."""
    msg = PointCloud2()
    msg.header.stamp = stamp
    msg.header.frame_id = frame
    msg.height, msg.width = 1, 4
    msg.fields = [PointField("x", 0, PointField.FLOAT32, 1), PointField("y", 4, PointField.FLOAT32, 1),
                  PointField("z", 8, PointField.FLOAT32, 1),
                  PointField("label", 12, PointField.UINT32, 1)]
    msg.point_step, msg.row_step = 16, 64
    msg.is_dense = True
    msg.data = b"".join(struct.pack("<fffI", 0.02 * i, 0.0, 3.0, 1) for i in range(4))
    return msg


class Node:
    """evidential_mapping_node as a child process (rosrun execs the binary: the pid is the node)."""

    def __init__(self, name, log_path, **params):
        self.name = "/" + name
        args = ["rosrun", "evidential_octomap", "evidential_mapping_node", "__name:=" + name,
                "cloud_in:=/%s_cloud" % name]
        args += ["_%s:=%s" % (k, v) for k, v in params.items()]
        self.log_path = log_path
        self.log = open(log_path, "a")
        self.process = subprocess.Popen(args, stdout=self.log, stderr=subprocess.STDOUT)
        self.status = None
        self.sub = rospy.Subscriber(self.name + "/status", MappingStatus, self._keep, queue_size=10)
        rospy.wait_for_service(self.name + "/query", timeout=60)
        self.query = rospy.ServiceProxy(self.name + "/query", QueryMap)
        self.save = rospy.ServiceProxy(self.name + "/save_map", SaveMap)

    def _keep(self, msg):
        self.status = msg

    def wait_status(self, pred, timeout=30.0):
        deadline = time.time() + timeout
        while time.time() < deadline:
            s = self.status
            if s is not None and pred(s):
                return s
            time.sleep(0.02)
        return None

    def kill(self):
        self.process.send_signal(signal.SIGKILL)
        self.process.wait()
        self.close()

    def stop(self):
        self.process.send_signal(signal.SIGINT)
        try:
            self.process.wait(30)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        self.close()

    def close(self):
        self.sub.unregister()
        self.log.close()


class Feeder:
    """Publishes scan g with the sensor at (SPACING * g, 0, 0) (TF map -> <name>_sensor)."""

    def __init__(self, name):
        self.frame = name + "_sensor"
        self.pub = rospy.Publisher("/%s_cloud" % name, PointCloud2, queue_size=200)
        self.tf = tf2_ros.TransformBroadcaster()
        self.published = {}  # g -> wall time of publication
        self.dead = []

    def _connections(self):
        return [c for p in (self.pub, self.tf.pub_tf) for c in p.impl.connections]

    def forget_connections(self):
        """Called when the node dies: its sockets may still count as subscribers until a write
        fails, and a scan published into one of them is lost."""
        self.dead = self._connections()  # the objects, kept alive: ids could be reused

    def wait_connected(self, timeout=30.0):
        """Until the (re)started node subscribes to the clouds and to /tf over new connections
        (else the first scans are lost)."""
        dead = self.dead
        deadline = time.time() + timeout
        while time.time() < deadline:
            live = [p for p in (self.pub, self.tf.pub_tf)
                    if any(all(c is not d for d in dead) for c in p.impl.connections)]
            if len(live) == 2:
                time.sleep(0.2)
                return True
            time.sleep(0.05)
        return False

    def publish(self, g):
        stamp = rospy.Time.now()
        t = TransformStamped()
        t.header.stamp = stamp
        t.header.frame_id = "map"
        t.child_frame_id = self.frame
        t.transform.translation.x = SPACING * g
        t.transform.rotation.w = 1.0
        self.tf.sendTransform(t)
        self.pub.publish(cloud(stamp, self.frame))
        self.published[g] = time.time()


def scans_in_map(node, count):
    """Indices g < count whose voxel holds evidence in the node's map."""
    points = [Point(SPACING * g + 0.03, 0.0, 3.0) for g in range(count)]
    answer = node.query(points)
    return [g for g in range(count) if answer.labels[g] >= 0]


REPUBLISHED = []  # scans published more than once


def publish_until_mapped(node, feeder, g):
    """Publishes scan g until the node's map holds it (a copy again after 1 s): ROS 1 transport
    may drop a message silently, which is not what these tests are about."""
    for copy in range(20):
        if copy:
            REPUBLISHED.append(g)
        feeder.publish(g)
        deadline = time.time() + 1.0
        while time.time() < deadline:
            if scans_in_map(node, g + 1)[-1:] == [g]:
                return
            time.sleep(0.01)
    raise AssertionError("scan %d never reached the map" % g)


def files(directory):
    return sorted(os.listdir(directory))


class AutosaveRecoveryTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_autosave_recovery")
        cls.dir = tempfile.mkdtemp(prefix="evidential_autosave_")

    @classmethod
    def tearDownClass(cls):
        if not os.environ.get("EVIDENTIAL_KEEP_TEST_DIR"):
            shutil.rmtree(cls.dir, ignore_errors=True)

    def test_kill_minus_9_at_random_moments_resumes_from_the_newest_autosave(self):
        self.kill_and_resume("kill", {}, ["map.autosave.ot"])

    def test_kill_minus_9_of_a_local_map_resumes_from_the_newest_snapshot(self):
        # Scans 0.6 m apart, 3 m above the sensor: with a 3.5 m range and an 8 m radius, tiles
        # of 3.2 m leave for disk within seconds and the snapshot holds links of them.
        tiles = os.path.join(self.dir, "kill_local_tiles")
        self.kill_and_resume("kill_local", {"sensor_model/max_range": 3.5, "local_map/radius": 8.0,
                                            "local_map/tile_directory": tiles},
                             ["map.autosave.ot.local_map"])
        snapshots = files(os.path.join(self.dir, "kill_local", "map.autosave.ot.local_map"))
        self.assertEqual(len(snapshots), 1, snapshots)
        self.assertTrue(snapshots[0].startswith("snapshot_"), snapshots)
        # The killed nodes' tile directories went at the next start, the last one's at its stop.
        self.assertEqual(files(tiles), [])

    def kill_and_resume(self, name, extra_params, files_left):
        autosave = os.path.join(self.dir, name, "map.autosave.ot")
        log_path = os.path.join(self.dir, name + "_node.log")
        params = dict(autosave_period=PERIOD, autosave_path=autosave, insert_queue_size=100,
                      publish_rate=1.0, **extra_params)
        feeder = Feeder("autosave_" + name)
        rng = random.Random(20261201)
        g = 0                # next scan index
        resumed = 0          # scans in the map at the last start
        lost_seconds, lost_scans = [], []
        report = os.environ.get("EVIDENTIAL_AUTOSAVE_REPORT")
        for kill in range(KILLS + 1):
            before = open(log_path).read() if os.path.exists(log_path) else ""
            had_autosave = any(os.path.exists(autosave + e) for e in ("", ".local_map"))
            node = Node("autosave_" + name, log_path, **params)
            try:
                self.assertTrue(feeder.wait_connected())
                if kill > 0:
                    in_map = scans_in_map(node, max(feeder.published) + 1)
                    self.assertEqual(in_map, list(range(len(in_map))),
                                     "kill %d: the resumed map is not a prefix of the scans" % kill)
                    resumed_now = len(in_map)
                    log = open(log_path).read()[len(before):]
                    # Killed before its first autosave, the node starts empty (and lost at most
                    # one period); else it resumes.
                    self.assertIn(("autosave: resumed from " if had_autosave else
                                   "autosave: none at ") + autosave, log, log[-2000:])
                    self.assertNotIn("cannot resume", log)
                    # Lost: from the first scan not in the map to the last one inserted.
                    inserted_before_kill = last_inserted
                    self.assertGreaterEqual(resumed_now, resumed,
                                            "kill %d: an older autosave than before" % kill)
                    lost = max(0, inserted_before_kill - resumed_now)
                    span = (feeder.published[inserted_before_kill - 1] -
                            feeder.published[resumed_now]) if lost > 0 else 0.0
                    lost_scans.append(lost)
                    lost_seconds.append(span)
                    self.assertLessEqual(span, PERIOD + WRITE_SLACK,
                                         "kill %d: %d scans (%.2f s) lost" % (kill, lost, span))
                    if report:
                        with open(report, "a") as f:
                            f.write(json.dumps({"mode": name, "kill": kill, "lost_scans": lost,
                                                "lost_s": round(span, 3),
                                                "resumed_scans": resumed_now}) + "\n")
                    resumed = resumed_now
                    g = resumed_now  # the scans lost are published again
                if kill == KILLS:
                    break
                mapping_for = rng.uniform(0.3, 3.0 * PERIOD + 0.5)
                t_end = time.time() + mapping_for
                while time.time() < t_end:
                    publish_until_mapped(node, feeder, g)
                    g += 1
                    time.sleep(1.0 / RATE)
                # Scans 0 .. g-1 are in the map; the kill lands while it maps, at a random phase
                # of the autosave period.
                last_inserted = g
                feeder.forget_connections()
                node.kill()
                node = None
                g = last_inserted
            finally:
                if node is not None:
                    node.stop()
        # Started once more: it autosaves and removes whatever a killed writer left.
        node = Node("autosave_" + name, log_path, **params)
        self.assertTrue(feeder.wait_connected())
        feeder.publish(g)
        self.assertIsNotNone(node.wait_status(lambda s: s.autosaves_written >= 1, 10 * PERIOD + 30))
        tiles_on_disk = node.status.local_map_tiles_on_disk
        node.stop()
        self.assertEqual(files(os.path.dirname(autosave)), files_left)
        if extra_params:
            self.assertGreater(tiles_on_disk, 0, "no tile left memory: the snapshot held none")
        if lost_seconds:
            print("[autosave %s] %d kills, period %.1f s: seconds lost mean %.2f, max %.2f; scans "
                  "lost mean %.1f, max %d; republished %s" % (name, len(lost_seconds), PERIOD,
                                              sum(lost_seconds) / len(lost_seconds),
                                              max(lost_seconds),
                                              sum(lost_scans) / len(lost_scans), max(lost_scans),
                                              REPUBLISHED))

    def test_saves_into_a_full_or_read_only_filesystem_fail_cleanly_and_mapping_goes_on(self):
        mount_dir = os.path.join(self.dir, "small_fs")
        os.makedirs(mount_dir)
        mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", mount_dir],
                                 stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        if mounted.returncode != 0:
            self.skipTest("cannot mount a tmpfs here (%s): needs root" % mounted.stdout.strip())
        node = None
        try:
            autosave = os.path.join(mount_dir, "map.autosave.ot")
            saved = os.path.join(mount_dir, "saved.ot")
            node = Node("autosave_disk", os.path.join(self.dir, "disk_node.log"),
                        autosave_period=0.5, autosave_path=autosave, insert_queue_size=100)
            feeder = Feeder("autosave_disk")
            self.assertTrue(feeder.wait_connected())
            g = 0
            for _ in range(20):
                publish_until_mapped(node, feeder, g)
                g += 1
            self.assertIsNotNone(node.wait_status(lambda s: s.autosaves_written >= 1))
            self.assertTrue(node.save(saved).success)
            previous = {p: open(p, "rb").read() for p in (saved, autosave)}
            # Nearly full: a filler leaves 2 KiB; the map (> 2 KiB with its header) cannot fit.
            # An autosave that fails while the filler grows removes its temporary and frees that
            # space again, so the filler tops up after two autosave periods.
            filler = os.path.join(mount_dir, "filler")
            with open(filler, "ab", buffering=0) as f:
                for _ in range(2):
                    try:
                        while True:
                            f.write(b"x" * 4096)
                    except OSError:
                        pass
                    time.sleep(2.5 * 0.5)
            os.truncate(filler, os.path.getsize(filler) - 2048)
            for case, reason in (("full", "No space left on device"),
                                 ("read-only", "Read-only file system")):
                if case == "read-only":
                    # The filler stays: with room again an autosave could land before the
                    # remount. A remount while a write is open fails (busy): try again.
                    for _ in range(50):
                        if subprocess.run(["mount", "-o", "remount,ro", mount_dir]).returncode == 0:
                            break
                        time.sleep(0.1)
                    else:
                        self.fail("cannot remount %s read-only" % mount_dir)
                failed_before = node.status.autosaves_failed
                inserted_before = node.status.clouds_inserted
                reply = node.save(saved)
                self.assertFalse(reply.success, case)
                self.assertIn(saved, reply.message)
                self.assertIn(reason, reply.message)
                for _ in range(20):  # the node goes on mapping
                    publish_until_mapped(node, feeder, g)
                    g += 1
                # (An autosave begun before the remount may still fail for the full disk.)
                status = node.wait_status(lambda s: s.clouds_inserted >= inserted_before + 20 and
                                          s.autosaves_failed > failed_before and
                                          reason in s.last_error)
                last = node.status
                self.assertIsNotNone(status, "%s: no failed autosave or mapping stopped (inserted "
                                     "%s of %d, autosaves failed %s of > %d, last error %r)" % (
                                         case, last and last.clouds_inserted, inserted_before + 20,
                                         last and last.autosaves_failed, failed_before,
                                         last and last.last_error))
                self.assertIn(reason, status.last_error)
                for path, data in previous.items():
                    self.assertEqual(open(path, "rb").read(), data, "%s: %s changed" % (case, path))
                self.assertEqual([f for f in files(mount_dir) if ".evidential-tmp." in f], [])
        finally:
            if node is not None:
                node.stop()
            subprocess.run(["umount", "-l", mount_dir])


if __name__ == "__main__":
    rostest.rosrun("evidential_octomap", "autosave_recovery", AutosaveRecoveryTest)
