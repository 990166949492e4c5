#!/usr/bin/python3
"""Streams a SemanticKITTI-layout directory as PointCloud2 with per-point evidence plus TF.

    rosrun evidential_octomap play_semantickitti.py _data:=<dir> _rate:=2 _loop:=false
    rosrun evidential_octomap play_semantickitti.py _bag:=/tmp/kitti08.bag   # write a bag instead

Directory layout: velodyne/NNNNNN.bin (float32 x y z remission), predictions/NNNNNN.label
(uint32, lower 16 bits = raw class id) or labels/ when ~labels_dir says so, poses.txt (camera-0
poses, 12 floats per line), calib.txt (Tr: velodyne -> camera). The files are read by the
package's one SemanticKITTI reader (libevidential_octomap_evaluation.so, through ctypes), as the
CLI, the benchmarks and the Python package read them.

Published (REP 105 names):
  velodyne_points  (remap to the mapping node's cloud_in): fields x, y, z (float32) and
              `evidence` (float32, count C) in frame ~sensor_frame (velodyne);
  /tf      map -> velodyne, T_world_velo(i) = inv(Tr) * P(i) * Tr (semantic-kitti-api);
  ~evidence_source (std_msgs/String, latched) says how the evidence was made.

The bundled data ships hard argmax predictions only. ~evidence chooses how they become evidence:
  learned  the learned evidence head (docs/learned_evidence.md), run in C++ through ctypes on the
           package's libevidential_octomap_evidence.so: a small evidential model on each scan's geometry and
           predictions, CROSS-FITTED (a scan's evidence never comes from a model that saw its
           labels); ~learned_model (default: config/learned/<dataset>.model);
  onehot   DERIVED: one-hot of magnitude ~evidence_magnitude on the predicted class.
Every output says which (~evidence_source).
"""
import ctypes
import os
import sys

import numpy as np
import rospy
import yaml
from geometry_msgs.msg import TransformStamped
from sensor_msgs.msg import PointCloud2, PointField
from std_msgs.msg import Header, String
from tf2_msgs.msg import TFMessage


def load_class_table(path):
    """(class names, dataset name) of a class table YAML."""
    with open(path) as f:
        table = yaml.safe_load(f)
    return [c["name"] for c in table["classes"]], table.get("dataset", "")


def _library(name, what):
    try:
        return ctypes.CDLL(name)
    except OSError as e:
        raise RuntimeError("%s needs %s of this package on the library path (source the catkin "
                           "workspace's devel/setup.bash): %s" % (what, name, e))


def learned_evidence_function(model_path, num_classes):
    """evidence(xyz, remission, classes) -> N x C float32 by the core library's C entry point."""
    lib = _library("libevidential_octomap_evidence.so", "learned evidence")
    fn = lib.evidential_octomap_learned_evidence
    floats = ctypes.POINTER(ctypes.c_float)
    fn.restype = ctypes.c_int
    fn.argtypes = [ctypes.c_char_p, floats, floats, ctypes.POINTER(ctypes.c_int32), ctypes.c_size_t,
                   ctypes.c_int, floats, ctypes.c_char_p, ctypes.c_size_t]

    def evidence(xyz, remission, classes):
        xyz = np.ascontiguousarray(xyz, dtype=np.float32)
        remission = np.ascontiguousarray(remission, dtype=np.float32)
        predicted = np.ascontiguousarray(classes, dtype=np.int32)
        out = np.empty((len(predicted), num_classes), dtype=np.float32)
        error = ctypes.create_string_buffer(1024)
        if fn(model_path.encode(), xyz.ctypes.data_as(floats), remission.ctypes.data_as(floats),
              predicted.ctypes.data_as(ctypes.POINTER(ctypes.c_int32)), len(predicted), num_classes,
              out.ctypes.data_as(floats), error, len(error)) != 0:
            raise RuntimeError("learned evidence: %s" % error.value.decode())
        return out
    return evidence


class DatasetReader:
    """A SemanticKITTI-layout directory through the evaluation library's reader (dataset_c.h):
    load(i) -> (name, xyz N x 3 in the sensor frame, remission N, classes N, T_W_S 4 x 4)."""

    def __init__(self, path, class_table, classes_from):
        self._lib = lib = _library("libevidential_octomap_evaluation.so", "reading datasets")
        lib.evidential_octomap_dataset_open.restype = ctypes.c_void_p
        lib.evidential_octomap_dataset_open.argtypes = [ctypes.c_char_p, ctypes.c_char_p,
                                                        ctypes.c_char_p, ctypes.c_size_t]
        lib.evidential_octomap_dataset_close.argtypes = [ctypes.c_void_p]
        lib.evidential_octomap_dataset_size.restype = ctypes.c_size_t
        lib.evidential_octomap_dataset_size.argtypes = [ctypes.c_void_p]
        lib.evidential_octomap_dataset_load.restype = ctypes.c_longlong
        lib.evidential_octomap_dataset_load.argtypes = [ctypes.c_void_p, ctypes.c_size_t,
                                                        ctypes.c_char_p, ctypes.c_char_p,
                                                        ctypes.c_size_t]
        lib.evidential_octomap_dataset_scan.argtypes = [ctypes.c_void_p] + [ctypes.c_void_p] * 5 + [
            ctypes.c_size_t]
        error = ctypes.create_string_buffer(2048)
        self._handle = lib.evidential_octomap_dataset_open(path.encode(), class_table.encode(),
                                                           error, len(error))
        if not self._handle:
            raise RuntimeError(error.value.decode())
        self._classes_from = classes_from.encode()

    def __len__(self):
        return self._lib.evidential_octomap_dataset_size(self._handle)

    def load(self, i):
        error = ctypes.create_string_buffer(2048)
        n = self._lib.evidential_octomap_dataset_load(self._handle, i, self._classes_from, error,
                                                      len(error))
        if n < 0:
            raise RuntimeError(error.value.decode())
        xyz = np.empty((n, 3), np.float32)
        remission = np.empty(n, np.float32)
        classes = np.empty(n, np.int32)
        pose = np.empty((4, 4), np.float64)
        name = ctypes.create_string_buffer(256)
        self._lib.evidential_octomap_dataset_scan(self._handle, xyz.ctypes.data, remission.ctypes.data,
                                                  classes.ctypes.data, pose.ctypes.data, name,
                                                  len(name))
        return name.value.decode(), xyz, remission, classes, pose

    def __del__(self):
        if getattr(self, "_handle", None):
            self._lib.evidential_octomap_dataset_close(self._handle)


def quaternion_from_matrix(r):
    """(x, y, z, w) of a rotation matrix (Shepperd's method)."""
    t = np.trace(r)
    if t > 0:
        s = np.sqrt(t + 1.0) * 2
        return ((r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, 0.25 * s)
    i = int(np.argmax(np.diag(r)))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = np.sqrt(1.0 + r[i, i] - r[j, j] - r[k, k]) * 2
    q = [0.0, 0.0, 0.0]
    q[i] = 0.25 * s
    q[j] = (r[j, i] + r[i, j]) / s
    q[k] = (r[k, i] + r[i, k]) / s
    w = (r[k, j] - r[j, k]) / s
    return (q[0], q[1], q[2], w)


def make_cloud(xyz, evidence, header):
    n, c = evidence.shape
    dtype = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("evidence", "<f4", (c,))])
    data = np.empty(n, dtype=dtype)
    data["x"], data["y"], data["z"] = xyz[:, 0], xyz[:, 1], xyz[:, 2]
    data["evidence"] = evidence
    msg = PointCloud2()
    msg.header = header
    msg.height, msg.width = 1, n
    msg.fields = [PointField("x", 0, PointField.FLOAT32, 1), PointField("y", 4, PointField.FLOAT32, 1),
                  PointField("z", 8, PointField.FLOAT32, 1),
                  PointField("evidence", 12, PointField.FLOAT32, c)]
    msg.is_bigendian = False
    msg.point_step = dtype.itemsize
    msg.row_step = msg.point_step * n
    msg.is_dense = True
    msg.data = data.tobytes()
    return msg


def make_tf(pose, stamp, world, sensor):
    t = TransformStamped()
    t.header.stamp = stamp
    t.header.frame_id = world
    t.child_frame_id = sensor
    t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = pose[:3, 3]
    q = quaternion_from_matrix(pose[:3, :3])
    t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z, t.transform.rotation.w = q
    return t


def default_path(rel):
    import rospkg
    return os.path.join(rospkg.RosPack().get_path("evidential_octomap"), rel)


def argv_params():
    """`_name:=value` arguments, typed as YAML (what rospy would put on the parameter server)."""
    params = {}
    for arg in sys.argv[1:]:
        if arg.startswith("_") and ":=" in arg:
            name, _, value = arg[1:].partition(":=")
            params[name] = yaml.safe_load(value)
    return params


def main():
    # Writing a bag needs no roscore: then the `_name:=value` arguments are read directly.
    offline = "bag" in argv_params() and argv_params()["bag"]
    if offline:
        params = argv_params()
        get_param = lambda name, default: params.get(name[1:], default)  # noqa: E731
    else:
        rospy.init_node("play_semantickitti")
        get_param = rospy.get_param
    data = get_param("~data", "") or default_path("data/semantickitti_08_first10")
    classes = get_param("~classes", "") or default_path("config/classes_semantickitti.yaml")
    labels_dir = get_param("~labels_dir", "predictions")
    magnitude = float(get_param("~evidence_magnitude", 20.0))
    evidence_kind = get_param("~evidence", "onehot")
    learned_model = get_param("~learned_model", "")
    rate = float(get_param("~rate", 1.0))
    loop = bool(get_param("~loop", False))
    bag_path = get_param("~bag", "")
    world = get_param("~world_frame", "map")
    sensor = get_param("~sensor_frame", "velodyne")
    first = int(get_param("~first", 0))
    count = int(get_param("~count", -1))
    start_delay = float(get_param("~start_delay", 1.0))

    names, dataset = load_class_table(classes)
    num_classes = len(names)
    if evidence_kind not in ("onehot", "learned"):
        raise RuntimeError("~evidence must be onehot or learned, not %r" % evidence_kind)
    if labels_dir not in ("predictions", "labels"):
        raise RuntimeError("~labels_dir must be predictions or labels, not %r" % labels_dir)
    reader = DatasetReader(data, classes, labels_dir)
    scans = list(range(len(reader)))
    scans = scans[first:] if count < 0 else scans[first:first + count]
    if evidence_kind == "learned":
        learned_model = learned_model or os.path.join(os.path.dirname(classes), "learned",
                                                      dataset + ".model")
        learned = learned_evidence_function(learned_model, num_classes)
        source = ("learned (cross-fitted): evidential MLP on each scan's geometry and the hard "
                  "predictions in %s/, each scan's evidence from the model fold(s) not trained on "
                  "its labels (model %s)" % (labels_dir, learned_model))
    else:
        source = ("derived: one-hot evidence of magnitude %g from the hard predictions in %s/ "
                  "(raw ids -> %d classes via %s); not a network's evidential output"
                  % (magnitude, labels_dir, num_classes, os.path.basename(classes)))
    log = print if offline else rospy.loginfo
    (print if offline else rospy.logwarn)(
        "play_semantickitti: %d scans from %s; evidence is %s" % (len(scans), data, source))

    def scan_messages(index, stamp):
        name, xyz, remission, cls, pose = reader.load(index)
        if evidence_kind == "learned":
            evidence = learned(xyz, remission, cls)
        else:
            evidence = np.zeros((len(cls), num_classes), dtype=np.float32)
            evidence[np.arange(len(cls)), cls] = magnitude
        header = Header(stamp=stamp, frame_id=sensor)
        return make_cloud(xyz, evidence, header), make_tf(pose, stamp, world, sensor), pose

    if bag_path:
        import rosbag
        with rosbag.Bag(bag_path, "w") as bag:
            t0 = rospy.Time.from_sec(1.0)
            bag.write("/evidence_source", String(source), t0)
            for i, index in enumerate(scans):
                stamp = t0 + rospy.Duration.from_sec(i / max(rate, 1e-3))
                cloud, tf, _ = scan_messages(index, stamp)
                bag.write("/tf", TFMessage([tf]), stamp)
                bag.write("/velodyne_points", cloud, stamp)
                log("bag: scan %d (%d points)" % (index, cloud.width))
        log("wrote %d scans to %s (topics /velodyne_points, /tf, /evidence_source)"
            % (len(scans), bag_path))
        return

    cloud_pub = rospy.Publisher("velodyne_points", PointCloud2, queue_size=2)
    tf_pub = rospy.Publisher("/tf", TFMessage, queue_size=10)
    source_pub = rospy.Publisher("~evidence_source", String, queue_size=1, latch=True)
    source_pub.publish(String(source))
    rospy.sleep(start_delay)  # let subscribers connect
    period = rospy.Duration.from_sec(1.0 / rate) if rate > 0 else rospy.Duration(0)
    # Looping replays each cloud from memory (~12 MB a scan) with a new stamp: learned evidence
    # takes the player ~1 s a scan to compute, which would otherwise bound the replay rate.
    clouds = {}
    next_start = rospy.Time.now()
    while not rospy.is_shutdown():
        for index in scans:
            if rospy.is_shutdown():
                break
            stamp = rospy.Time.now()
            if index in clouds:
                cloud, pose = clouds[index]
                cloud.header.stamp = stamp
                tf = make_tf(pose, stamp, world, sensor)
            else:
                cloud, tf, pose = scan_messages(index, stamp)
                if loop:
                    clouds[index] = cloud, pose
            # TF first; the mapping node's tf2 MessageFilter holds the cloud until it has it.
            tf_pub.publish(TFMessage([tf]))
            cloud_pub.publish(cloud)
            rospy.loginfo("scan %d: %d points", index, cloud.width)
            if period > rospy.Duration(0):  # a steady rate: the time a scan took is not added
                next_start = max(next_start + period, rospy.Time.now() - period)
                remaining = next_start - rospy.Time.now()
                if remaining > rospy.Duration(0):
                    rospy.sleep(remaining)
        if not loop:
            break
    # Keep TF alive a little for late subscribers, then stop.
    rospy.loginfo("play_semantickitti: done (%d scans)", len(scans))
    rospy.spin() if rospy.get_param("~stay", True) else None


if __name__ == "__main__":
    try:
        main()
    except rospy.ROSInterruptException:
        pass
    except Exception as e:  # a clear message, not a traceback, for bad directories
        print("play_semantickitti: %s" % e, file=sys.stderr)
        sys.exit(1)
