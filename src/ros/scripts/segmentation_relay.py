#!/usr/bin/python3
"""Turns a raw LiDAR PointCloud2 into one that evidential_mapping_node maps: runs a segmentation
model on every cloud and republishes it with a per-point `evidence` field (float32, count C).

    rosrun evidential_octomap segmentation_relay.py cloud_in:=/os_cloud_node/points \
        _classes:=$(rospack find evidential_octomap)/config/classes_semantickitti.yaml

Subscribed  cloud_in   (sensor_msgs/PointCloud2) the sensor's cloud: x, y, z and whatever the
                       model reads (the learned example: `intensity` and a `label` field);
Published   cloud_out  (sensor_msgs/PointCloud2) x, y, z, evidence[C]; same header (stamp and
                       sensor frame), so the mapper looks up TF for the instant of the scan.

~model chooses the model:
  learned (default)  the package's learned evidence head (docs/learned_evidence.md): turns a
                     network's hard per-point predictions (`label`, class ids of ~classes) plus
                     the scan's geometry into evidence; ~learned_model is its file;
  FILE.py:CLASS      your model: a class built as CLASS(class_names, get_param) whose
                     __call__(points) returns an N x C float32 array of evidence >= 0, where
                     `points` maps every field name of the cloud (x, y, z, intensity, ...) to a
                     numpy array of its N values. examples/relay_model_template.py is one.
A cloud the model cannot read is skipped with a warning; the relay keeps running.
"""
import importlib.util
import os
import sys

import numpy as np
import rospy
from sensor_msgs.msg import PointCloud2, PointField

# The learned head's ctypes wrapper and the class-table reader live in the dataset player.
sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
from play_semantickitti import learned_evidence_function, load_class_table  # noqa: E402

NUMPY_TYPES = {PointField.INT8: "i1", PointField.UINT8: "u1", PointField.INT16: "<i2",
               PointField.UINT16: "<u2", PointField.INT32: "<i4", PointField.UINT32: "<u4",
               PointField.FLOAT32: "<f4", PointField.FLOAT64: "<f8"}


def read_fields(msg):
    """Field name -> N values (N x count for count > 1) of an organised or unorganised cloud."""
    if msg.is_bigendian:
        raise ValueError("big-endian clouds are not supported")
    names, formats, offsets = [], [], []
    for f in msg.fields:
        if f.datatype not in NUMPY_TYPES:
            raise ValueError("field %r has unknown datatype %d" % (f.name, f.datatype))
        names.append(f.name)
        formats.append((NUMPY_TYPES[f.datatype], (f.count,)) if f.count > 1 else NUMPY_TYPES[f.datatype])
        offsets.append(f.offset)
    dtype = np.dtype({"names": names, "formats": formats, "offsets": offsets,
                      "itemsize": msg.point_step})
    rows = np.frombuffer(bytes(msg.data), dtype=np.uint8)
    if rows.size < msg.row_step * msg.height:
        raise ValueError("truncated data: %d bytes for %d rows of %d" % (rows.size, msg.height, msg.row_step))
    rows = rows[:msg.row_step * msg.height].reshape(msg.height, msg.row_step)
    points = rows[:, :msg.width * msg.point_step].copy().view(dtype).reshape(-1)
    return {name: points[name] for name in names}


def evidence_cloud(header, xyz, evidence):
    """A PointCloud2 of x, y, z and evidence[C] (float32), the layout the mapper reads."""
    n, c = evidence.shape
    dtype = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("evidence", "<f4", (c,))])
    data = np.empty(n, dtype=dtype)
    data["x"], data["y"], data["z"] = xyz
    data["evidence"] = evidence
    msg = PointCloud2(header=header, height=1, width=n, is_bigendian=False, is_dense=False,
                      point_step=dtype.itemsize, row_step=dtype.itemsize * n, data=data.tobytes())
    msg.fields = [PointField("x", 0, PointField.FLOAT32, 1), PointField("y", 4, PointField.FLOAT32, 1),
                  PointField("z", 8, PointField.FLOAT32, 1),
                  PointField("evidence", 12, PointField.FLOAT32, c)]
    return msg


class LearnedHead:
    """The bundled example: the learned evidence head on a network's hard predictions."""

    def __init__(self, class_names, get_param):
        self.num_classes = len(class_names)
        classes = get_param("~classes")
        dataset = load_class_table(classes)[1]
        model = get_param("~learned_model", "") or get_param("~model_file", "") or os.path.join(
            os.path.dirname(classes), "learned", dataset + ".model")
        self.label_field = get_param("~label_field", "label")
        self.intensity_field = get_param("~intensity_field", "intensity")
        self.evidence = learned_evidence_function(model, self.num_classes)
        rospy.loginfo("segmentation_relay: learned evidence head %s", model)

    def __call__(self, points):
        if self.label_field not in points:
            raise ValueError("the learned head needs the network's hard predictions in field %r "
                             "(fields: %s)" % (self.label_field, ", ".join(points)))
        xyz = np.stack([points["x"], points["y"], points["z"]], axis=1).astype(np.float32)
        intensity = points.get(self.intensity_field, np.zeros(len(xyz), np.float32))
        labels = points[self.label_field].astype(np.int64)
        labels[(labels < 0) | (labels >= self.num_classes)] = -1  # "no prediction"
        return self.evidence(xyz, np.asarray(intensity, np.float32), labels)


def load_model(spec, class_names, get_param):
    """`learned` or `FILE.py:CLASS` (a user's model class)."""
    if spec == "learned":
        return LearnedHead(class_names, get_param)
    path, _, name = spec.rpartition(":")
    if not path.endswith(".py") or not name:
        raise ValueError("~model must be `learned` or FILE.py:CLASS, not %r" % spec)
    module_spec = importlib.util.spec_from_file_location("relay_user_model", path)
    module = importlib.util.module_from_spec(module_spec)
    module_spec.loader.exec_module(module)
    return getattr(module, name)(class_names, get_param)


def main():
    rospy.init_node("segmentation_relay")
    classes = rospy.get_param("~classes", "")
    if not classes:
        import rospkg
        classes = os.path.join(rospkg.RosPack().get_path("evidential_octomap"),
                               "config", "classes_semantickitti.yaml")
        rospy.set_param("~classes", classes)
    class_names = load_class_table(classes)[0]
    model = load_model(rospy.get_param("~model", "learned"), class_names, rospy.get_param)
    pub = rospy.Publisher("cloud_out", PointCloud2, queue_size=2)
    counts = {"relayed": 0, "skipped": 0}

    def relay(msg):
        try:
            points = read_fields(msg)
            for axis in "xyz":
                if axis not in points:
                    raise ValueError("missing field %r" % axis)
            evidence = np.asarray(model(points), dtype=np.float32)
            if evidence.shape != (len(points["x"]), len(class_names)):
                raise ValueError("the model returned shape %s, expected (%d, %d)"
                                 % (evidence.shape, len(points["x"]), len(class_names)))
            evidence = np.where(np.isfinite(evidence), np.maximum(evidence, 0), 0)
        except Exception as e:  # a bad cloud or a model error: say why, keep relaying
            counts["skipped"] += 1
            rospy.logwarn_throttle(5, "segmentation_relay: cloud skipped (%d so far): %s"
                                   % (counts["skipped"], e))
            return
        pub.publish(evidence_cloud(msg.header, (points["x"], points["y"], points["z"]), evidence))
        counts["relayed"] += 1
        rospy.loginfo_throttle(10, "segmentation_relay: %d clouds relayed" % counts["relayed"])

    # queue_size 1: a model slower than the sensor works on the newest cloud, never a backlog.
    rospy.Subscriber("cloud_in", PointCloud2, relay, queue_size=rospy.get_param("~queue_size", 1),
                     buff_size=1 << 26)
    rospy.spin()


if __name__ == "__main__":
    try:
        main()
    except rospy.ROSInterruptException:
        pass
    except Exception as e:  # a clear start-up error (bad ~model, class table, model file)
        print("segmentation_relay: %s" % e, file=sys.stderr)
        sys.exit(1)
