"""Map ROS 1 and ROS 2 bags, and write datasets as bags, with no ROS installed (rosbags).

    # a ROS 1 .bag or a ROS 2 bag directory (MCAP or sqlite3) -> map.ot, summary, pictures
    python -m evidential_octomap.bag map BAG --classes config/classes_semantickitti.yaml \\
        --frame map --out out/bag --topic /velodyne_points/evidence [--foxglove]
    # clouds without a semantic field through a model first (the bundled example or your own)
    python -m evidential_octomap.bag map BAG ... --topic /velodyne_points --model learned \\
        --predictions data/semantickitti_08_first10
    python -m evidential_octomap.bag map BAG ... --topic /velodyne_points --model my.py:evidence
    # a SemanticKITTI-layout directory -> a bag (raw and evidence clouds, /tf, /tf_static, /clock)
    python -m evidential_octomap.bag write data/semantickitti_08_first10 out/kitti.bag --ros1 \\
        --classes config/classes_semantickitti.yaml
    python -m evidential_octomap.bag write data/semantickitti_08_first10 out/kitti_mcap --ros2

Each cloud is read by the node's field rules (pointcloud2.py), placed by the sensor pose at its
stamp from /tf and /tf_static (tf_buffer.py) and inserted into an EvidentialOcTree; a cloud that
cannot be mapped (no TF at its stamp, a malformed field, no semantic field and no model) is
reported with the reason and skipped, and mapping goes on. ``--foxglove`` serves the map live to
Foxglove while it is built (foxglove_view.py). Needs ``pip install ".[bags]"``.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence

import numpy as np

from . import _core, pointcloud2
from .batch import config_overrides
from .models import DatasetPredictions, LearnedEvidence, default_learned_model, load_callable
from .tf_buffer import TfBuffer, TfError, quaternion

POINTCLOUD2 = "sensor_msgs/msg/PointCloud2"
TFMESSAGE = "tf2_msgs/msg/TFMessage"


def _rosbags():
    try:
        import rosbags  # noqa: F401
    except ImportError:
        raise SystemExit("evidential_octomap.bag needs rosbags: pip install \"evidential-octomap"
                         "[bags]\" (or pip install rosbags)") from None


# --- progress -------------------------------------------------------------------------------
class _Progress:
    """tqdm when it is installed, else one line rewritten on stderr; nothing when disabled."""

    def __init__(self, total: int, enabled: bool, what: str = "mapping"):
        self.enabled, self.total, self.count, self.what = enabled, total, 0, what
        self.bar = None
        self.t0 = time.monotonic()
        if enabled:
            try:
                from tqdm import tqdm
                self.bar = tqdm(total=total, desc=what, unit="cloud", file=sys.stderr)
            except ImportError:
                pass

    def tick(self, note: str = ""):
        self.count += 1
        if not self.enabled:
            return
        if self.bar is not None:
            self.bar.update(1)
            if note:
                self.bar.set_postfix_str(note, refresh=False)
            return
        rate = self.count / max(time.monotonic() - self.t0, 1e-9)
        width = 30
        done = int(width * self.count / max(self.total, 1))
        sys.stderr.write(f"\r{self.what} [{'#' * done}{'.' * (width - done)}] {self.count}/"
                         f"{self.total} {rate:.2f} cloud/s {note[:40]}")
        sys.stderr.flush()

    def close(self):
        if self.bar is not None:
            self.bar.close()
        elif self.enabled:
            sys.stderr.write("\n")


# --- reading --------------------------------------------------------------------------------
def stamp_ns(stamp) -> int:
    return int(stamp.sec) * 1_000_000_000 + int(getattr(stamp, "nanosec", 0))


def describe_bag(path: Path) -> str:
    if path.is_dir():
        meta = path / "metadata.yaml"
        storage = "?"
        if meta.is_file():
            for line in meta.read_text().splitlines():
                if "storage_identifier" in line:
                    storage = line.split(":", 1)[1].strip()
                    break
        return f"ROS 2 bag ({storage})"
    return "ROS 1 bag"


def _reader(path: Path):
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore
    return AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE))


def read_tf(reader) -> TfBuffer:
    """Every /tf and /tf_static transform of the bag."""
    tf = TfBuffer()
    conns = [c for c in reader.connections if c.msgtype == TFMESSAGE]
    if not conns:  # messages(connections=[]) would read every connection
        return tf
    for conn, _, raw in reader.messages(connections=conns):
        tf.add_message(reader.deserialize(raw, conn.msgtype), static=conn.topic == "/tf_static")
    return tf


def read_evidence_source(reader) -> Optional[str]:
    """The bag's /evidence_source (std_msgs/String, as `write` and the ROS player record it)."""
    conns = [c for c in reader.connections
             if c.topic == "/evidence_source" and c.msgtype == "std_msgs/msg/String"]
    text = None
    if not conns:  # messages(connections=[]) would read every connection
        return text
    for conn, _, raw in reader.messages(connections=conns):
        text = reader.deserialize(raw, conn.msgtype).data
    return text


def cloud_topics(reader) -> Dict[str, int]:
    return {c.topic: c.msgcount for c in reader.connections if c.msgtype == POINTCLOUD2}


def first_cloud_frame(reader, conns) -> Optional[str]:
    """header.frame_id of the topic's first cloud (None for a topic without messages)."""
    for conn, _, raw in reader.messages(connections=conns):
        return reader.deserialize(raw, conn.msgtype).header.frame_id
    return None


def frame_problem(tf: TfBuffer, map_frame: str, cloud_frame: str) -> str:
    """Why the bag's TF can place no cloud of `cloud_frame` in `map_frame` ("" when it may).

    Checked once before mapping, so that a bag recorded with other frame names, or without TF,
    stops with the frame to fix instead of dropping every cloud one by one.
    """
    map_frame, cloud_frame = map_frame.lstrip("/"), cloud_frame.lstrip("/")
    if map_frame == cloud_frame:  # the clouds are in the map frame: no TF needed (as tf2)
        return ""
    frames = tf.frames
    if not frames:
        return (f"the bag has no TF (no tf2_msgs/TFMessage on /tf or /tf_static), so the clouds' "
                f"frame '{cloud_frame}' cannot be placed in the map frame '{map_frame}': record "
                f"/tf and /tf_static with the bag, or map in the clouds' frame (--frame "
                f"{cloud_frame})")
    if cloud_frame not in frames:
        return (f"the clouds' frame '{cloud_frame}' is not in the bag's TF (frames: "
                f"{', '.join(frames)}): the clouds cannot be placed in '{map_frame}'")
    if map_frame not in frames:
        return (f"the map frame '{map_frame}' is not in the bag's TF (frames: "
                f"{', '.join(frames)}): choose one of them with --frame")
    return ""


# --- mapping --------------------------------------------------------------------------------
@dataclass
class MapOptions:
    frame: str = "map"
    topic: Optional[str] = None
    resolution: float = 0.2
    config: dict = field(default_factory=dict)      # SemanticConfig fields by name
    input: str = "auto"                              # pointcloud2.INPUTS
    label_magnitude: float = _core.EVIDENCE_MAGNITUDE
    logit_transform: str = "softmax"
    probability_magnitude: float = _core.EVIDENCE_MAGNITUDE
    raw_labels: bool = False                         # `label` holds raw ids (learning map)
    max_clouds: Optional[int] = None
    calibration: Optional[str] = None                # a file `evidential_octomap calibrate` wrote


@dataclass
class BagMap:
    tree: object
    summary: dict


def map_bag(bag, classes, options: MapOptions = MapOptions(), model: Optional[Callable] = None,
            view=None, progress: bool = False) -> BagMap:
    """Maps every PointCloud2 of a topic of a bag; returns the tree and the summary.

    ``model(points, fields) -> (N, C) evidence`` is applied to clouds without a semantic field
    (models.py); ``view`` (e.g. a FoxgloveView) gets ``view.update(tree, points_S, pose, stamp,
    sensor_frame=, evidence=)`` after each insert and ``view.finish(tree)`` at the end.
    """
    _rosbags()
    path = Path(bag)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such bag (a ROS 1 .bag file or a ROS 2 bag directory)")
    if path.is_file() and path.suffix != ".bag":
        raise ValueError(f"{path}: a ROS 1 bag must be named *.bag (a ROS 2 bag is a directory)")
    C = classes.num_classes
    tree = _core.EvidentialOcTree(options.resolution, classes,
                                  _core.SemanticConfig(**options.config))
    if options.calibration:
        tree.apply_calibration(_core.read_calibration(options.calibration))
    seconds = dict(read=0.0, decode=0.0, model=0.0, tf=0.0, insert=0.0, view=0.0)
    dropped: List[dict] = []
    sources: Dict[str, int] = {}
    mapped = points_in = nonfinite = 0
    t_start = time.monotonic()
    with _reader(path) as reader:
        topics = cloud_topics(reader)
        topic = options.topic
        if topic is None:
            if len(topics) != 1:
                raise ValueError(f"{path}: {len(topics)} PointCloud2 topics "
                                 f"({', '.join(f'{t} ({n})' for t, n in topics.items()) or 'none'}"
                                 "): which one should be mapped? Choose it with --topic")
            topic = next(iter(topics))
        if topic not in topics:
            raise ValueError(f"{path}: no PointCloud2 topic '{topic}' (PointCloud2 topics: "
                             f"{', '.join(topics) or 'none'})")
        t0 = time.monotonic()
        tf = read_tf(reader)
        seconds["tf"] += time.monotonic() - t0
        declared = read_evidence_source(reader)
        conns = [c for c in reader.connections if c.topic == topic]
        frame0 = first_cloud_frame(reader, conns)
        problem = frame_problem(tf, options.frame, frame0) if frame0 is not None else ""
        if problem:
            raise ValueError(f"{path}: {problem}")
        total = topics[topic] if options.max_clouds is None else min(topics[topic],
                                                                    options.max_clouds)
        bar = _Progress(total, progress)
        index = -1
        t0 = time.monotonic()
        for conn, _, raw in reader.messages(connections=conns):
            if options.max_clouds is not None and index + 1 >= options.max_clouds:
                break
            index += 1
            msg = reader.deserialize(raw, conn.msgtype)
            t1 = time.monotonic()
            seconds["read"] += t1 - t0
            stamp = stamp_ns(msg.header.stamp)
            frame = msg.header.frame_id

            def drop(reason):
                dropped.append({"index": index, "stamp_ns": stamp, "frame": frame,
                                "reason": reason})
                bar.tick("dropped")

            try:
                cloud = pointcloud2.decode(
                    msg, C, options.input, options.label_magnitude, options.logit_transform,
                    options.probability_magnitude, classes if options.raw_labels else None)
            except pointcloud2.CloudError as e:
                seconds["decode"] += time.monotonic() - t1
                drop(f"malformed cloud: {e}")
                t0 = time.monotonic()
                continue
            t2 = time.monotonic()
            seconds["decode"] += t2 - t1
            evidence, source = cloud.evidence, cloud.source
            if evidence is None:
                if model is None:
                    drop("no semantic field: expected 'evidence' (float32, count "
                         f"{C}), 'evidence_0'..'evidence_{C - 1}', 'alpha', 'logits', "
                         f"'probabilities' or 'label' (fields: {', '.join(f.name for f in msg.fields)}); "
                         "pass --model to run a model on such clouds")
                    t0 = time.monotonic()
                    continue
                try:
                    evidence = np.asarray(model(cloud.points, cloud.fields), dtype=np.float32)
                except Exception as e:  # a user's model: report and go on
                    drop(f"model failed: {type(e).__name__}: {e}")
                    t0 = time.monotonic()
                    continue
                source = "model: " + getattr(model, "description", getattr(model, "__name__",
                                                                           type(model).__name__))
            t3 = time.monotonic()
            seconds["model"] += t3 - t2
            try:
                pose = tf.lookup(options.frame, frame, stamp)
            except TfError as e:
                seconds["tf"] += time.monotonic() - t3
                drop(str(e))
                t0 = time.monotonic()
                continue
            t4 = time.monotonic()
            seconds["tf"] += t4 - t3
            try:
                tree.insert_scan(cloud.points, evidence, pose=pose)
            except ValueError as e:
                seconds["insert"] += time.monotonic() - t4
                drop(f"evidence refused: {e}")
                t0 = time.monotonic()
                continue
            t5 = time.monotonic()
            seconds["insert"] += t5 - t4
            mapped += 1
            points_in += len(cloud.points)
            nonfinite += cloud.nonfinite_points
            sources[source] = sources.get(source, 0) + 1
            if view is not None:
                view.update(tree, cloud.points, pose, stamp, sensor_frame=frame, evidence=evidence)
                seconds["view"] += time.monotonic() - t5
            bar.tick()
            t0 = time.monotonic()
        bar.close()
    if view is not None:
        t0 = time.monotonic()
        view.finish(tree)
        seconds["view"] += time.monotonic() - t0
    wall = time.monotonic() - t_start
    first, last = tf.time_range()
    summary = {
        "bag": str(path),
        "format": describe_bag(path),
        "topic": topic,
        "frame": options.frame,
        "clouds": index + 1,
        "scans_mapped": mapped,
        "points_mapped": points_in,
        "points_nonfinite": nonfinite,
        "dropped": dropped,
        "evidence_sources": sources,
        "evidence_declared": declared,  # the bag's /evidence_source (how the evidence was made)
        "tf": {"frames": tf.frames, "first_ns": first, "last_ns": last},
        "seconds": {"total": wall, **seconds},
        "scans_per_s": mapped / wall if wall > 0 else 0.0,
        "map": {"resolution": tree.resolution, "classes": tree.num_classes, "rule": tree.rule,
                "leaves": tree.num_leaves, "semantic_nodes": tree.num_semantic_nodes,
                "memory_bytes": tree.memory_usage},
    }
    return BagMap(tree, summary)


def summary_markdown(s: dict) -> str:
    lines = [f"# Bag map: {s['bag']}", "",
             f"- {s['format']}, topic `{s['topic']}`, map frame `{s['frame']}`",
             f"- clouds: {s['clouds']}, mapped: {s['scans_mapped']}, dropped: {len(s['dropped'])}",
             f"- points mapped: {s['points_mapped']:,} ({s['points_nonfinite']:,} NaN/inf dropped)",
             "- evidence: " + "; ".join(f"{k} ({v} clouds)" for k, v in
                                          s["evidence_sources"].items())
             + (f"; the bag says: {s['evidence_declared']}" if s.get("evidence_declared") else ""),
             f"- time: {s['seconds']['total']:.2f} s, {s['scans_per_s']:.2f} scans/s ("
             + ", ".join(f"{k} {v:.2f} s" for k, v in s["seconds"].items() if k != "total")
             + ")",
             f"- map: {s['map']['leaves']:,} leaves, {s['map']['semantic_nodes']:,} with evidence, "
             f"{s['map']['memory_bytes'] / 1e6:.0f} MB, resolution {s['map']['resolution']} m, "
             f"rule {s['map']['rule']}"]
    if s["dropped"]:
        lines += ["", "## Dropped clouds", "", "| # | stamp [s] | frame | reason |",
                  "| --- | --- | --- | --- |"]
        for d in s["dropped"]:
            lines.append(f"| {d['index']} | {d['stamp_ns'] / 1e9:.9f} | {d['frame']} | "
                         f"{d['reason'].replace('|', '/')} |")
    return "\n".join(lines) + "\n"


def write_outputs(result: BagMap, classes, out, render: bool = True) -> List[str]:
    """map.ot, summary.json, summary.md and (with the renderer built in) the two pictures."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    result.tree.save(str(out / "map.ot"))
    written = ["map.ot", "summary.json", "summary.md"]
    s = result.summary
    if render:
        if hasattr(_core, "render_top_down"):
            caption = [f"{s['format']} {s['topic']} | {s['scans_mapped']} scans | rule "
                       f"{s['map']['rule']}",
                       "evidence: " + ("; ".join(s["evidence_sources"]) or "none")
                       + (f" | {s['evidence_declared']}" if s.get("evidence_declared") else "")]
            for mode in ("semantic", "uncertainty"):
                _core.render_top_down(result.tree, classes, str(out / f"{mode}.png"), mode,
                                      [f"{mode} | " + caption[0], caption[1]])
                written.append(f"{mode}.png")
        else:
            s["note"] = "pictures skipped: the module was built without OpenCV (render_top_down)"
    s["outputs"] = written
    (out / "summary.json").write_text(json.dumps(s, indent=2) + "\n")
    (out / "summary.md").write_text(summary_markdown(s))
    return written


# --- writing --------------------------------------------------------------------------------
@dataclass
class WriteOptions:
    ros2: bool = True
    storage: str = "mcap"            # ROS 2: mcap or sqlite3
    scans: Optional[int] = None      # the first N scans (None: all)
    evidence: str = "onehot"         # file, onehot, knn-vote or learned
    magnitude: float = _core.EVIDENCE_MAGNITUDE
    learned_model: Optional[str] = None
    rate: float = 10.0               # scans per second of bag time
    start_ns: int = 1_000_000_000    # stamp of the first scan
    outside_buffer: bool = False     # one more cloud 1 s after the last TF
    world_frame: str = "map"
    base_frame: str = "base_link"
    sensor_frame: str = "velodyne"
    base_to_sensor: tuple = (0.0, 0.0, 1.73)  # the sensor's mounting on base_link (translation)
    raw_topic: str = "/velodyne_points"
    evidence_topic: str = "/velodyne_points/evidence"


def _typestore(ros2: bool):
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore
    ts = get_typestore(Stores.ROS2_HUMBLE if ros2 else Stores.ROS1_NOETIC)
    if TFMESSAGE not in ts.types:  # rosbags' ROS 1 store lacks geometry2's tf2_msgs
        ts.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms", TFMESSAGE))
    return ts


class _BagWriter:
    """One writer for both ROS versions: connections by topic, messages by dataclass."""

    def __init__(self, out: Path, options: WriteOptions):
        self.ros2 = options.ros2
        self.ts = _typestore(self.ros2)
        if self.ros2:
            from rosbags.rosbag2 import StoragePlugin, Writer
            plugin = {"mcap": StoragePlugin.MCAP, "sqlite3": StoragePlugin.SQLITE3}[options.storage]
            self.writer = Writer(out, version=9, storage_plugin=plugin)
        else:
            from rosbags.rosbag1 import Writer
            self.writer = Writer(out)
        self.writer.open()
        self.conns = {}

    def connection(self, topic: str, msgtype: str, latched: bool = False):
        if topic not in self.conns:
            kwargs = {}
            if latched and self.ros2:
                kwargs["offered_qos_profiles"] = [_latched_qos()]
            elif latched:
                kwargs["latching"] = 1
            self.conns[topic] = self.writer.add_connection(topic, msgtype, typestore=self.ts,
                                                           **kwargs)
        return self.conns[topic]

    def write(self, topic: str, msgtype: str, msg, stamp: int, latched: bool = False):
        conn = self.connection(topic, msgtype, latched)
        data = (self.ts.serialize_cdr(msg, msgtype) if self.ros2
                else self.ts.serialize_ros1(msg, msgtype))
        self.writer.write(conn, stamp, data)

    def close(self):
        self.writer.close()

    # message builders
    def header(self, stamp: int, frame: str):
        T = self.ts.types
        time_msg = T["builtin_interfaces/msg/Time"](sec=stamp // 1_000_000_000,
                                                    nanosec=stamp % 1_000_000_000)
        if self.ros2:
            return T["std_msgs/msg/Header"](stamp=time_msg, frame_id=frame)
        return T["std_msgs/msg/Header"](seq=0, stamp=time_msg, frame_id=frame)

    def cloud(self, stamp: int, frame: str, columns: Dict[str, np.ndarray]):
        T = self.ts.types
        rows, step, data = pointcloud2.pack(columns)
        fields = [T["sensor_msgs/msg/PointField"](name=n, offset=o, datatype=d, count=c)
                  for n, o, d, c in rows]
        n = len(next(iter(columns.values())))
        return T[POINTCLOUD2](header=self.header(stamp, frame), height=1, width=n, fields=fields,
                              is_bigendian=False, point_step=step, row_step=step * n, data=data,
                              is_dense=True)

    def transform(self, stamp: int, parent: str, child: str, T_parent_child: np.ndarray):
        T = self.ts.types
        x, y, z = T_parent_child[:3, 3]
        qx, qy, qz, qw = quaternion(T_parent_child[:3, :3])
        return T["geometry_msgs/msg/TransformStamped"](
            header=self.header(stamp, parent), child_frame_id=child,
            transform=T["geometry_msgs/msg/Transform"](
                translation=T["geometry_msgs/msg/Vector3"](x=float(x), y=float(y), z=float(z)),
                rotation=T["geometry_msgs/msg/Quaternion"](x=float(qx), y=float(qy),
                                                           z=float(qz), w=float(qw))))


def _latched_qos():
    from rosbags.interfaces import (Qos, QosDurability, QosHistory, QosLiveliness,
                                    QosReliability, QosTime)
    forever = QosTime(sec=2147483647, nsec=4294967295)
    return Qos(history=QosHistory.KEEP_LAST, depth=1, reliability=QosReliability.RELIABLE,
               durability=QosDurability.TRANSIENT_LOCAL, deadline=forever, lifespan=forever,
               liveliness=QosLiveliness.AUTOMATIC, liveliness_lease_duration=forever,
               avoid_ros_namespace_conventions=False)


def scan_evidence(scan, classes, options: WriteOptions, learned=None) -> np.ndarray:
    """(N, C) evidence of a scan as the CLI derives it (no calibration), or learned."""
    if options.evidence == "learned":
        return learned.evidence(scan.points, scan.remission, scan.predicted)
    return _core.derive_evidence(scan, classes.num_classes, options.evidence, options.magnitude)


def write_bag(data_dir, out, classes, options: WriteOptions = WriteOptions(),
              classes_path=None, progress: bool = False) -> dict:
    """Writes a SemanticKITTI-layout directory as a bag; returns what was written.

    Topics: ``raw_topic`` (x, y, z, intensity float32: what a LiDAR driver publishes),
    ``evidence_topic`` (x, y, z and ``evidence`` float32 of count C), /tf (world -> base per
    scan), /tf_static (base -> sensor, latched), /clock and /evidence_source (std_msgs/String).
    """
    _rosbags()
    out = Path(out)
    if out.exists():
        raise FileExistsError(f"{out} exists; the bag writer does not overwrite")
    if not options.ros2 and out.suffix != ".bag":
        raise ValueError(f"{out}: a ROS 1 bag must be named *.bag (as ROS tools expect)")
    dataset = _core.Dataset.open(str(data_dir), classes)
    n = len(dataset) if options.scans is None else min(options.scans, len(dataset))
    learned = None
    if options.evidence == "learned":
        model_path = options.learned_model or default_learned_model(
            classes_path or "", classes)
        learned = _core.LearnedEvidenceModel.load(str(model_path))
        source = f"learned (cross-fitted): {model_path} on the hard predictions in predictions/"
    elif options.evidence == "file":
        source = "network evidence: the dataset's evidence files"
    else:
        source = (f"derived: {options.evidence} evidence of magnitude {options.magnitude:g} from "
                  "the hard predictions in predictions/ (no calibration); not a network's output")
    period = int(round(1e9 / options.rate))
    T_base_sensor = np.eye(4)
    T_base_sensor[:3, 3] = options.base_to_sensor
    T_sensor_base = np.linalg.inv(T_base_sensor)
    w = _BagWriter(out, options)
    T = w.ts.types
    string = T["std_msgs/msg/String"]
    stamps = []
    bar = _Progress(n, progress, "writing")
    try:
        w.write("/evidence_source", "std_msgs/msg/String", string(data=source),
                options.start_ns, latched=True)
        w.write("/tf_static", TFMESSAGE, T[TFMESSAGE](transforms=[w.transform(
            options.start_ns, options.base_frame, options.sensor_frame, T_base_sensor)]),
            options.start_ns, latched=True)
        last = None
        for i in range(n):
            scan = dataset.load(i)
            stamp = options.start_ns + i * period
            stamps.append(stamp)
            T_W_base = scan.pose @ T_sensor_base
            w.write("/clock", "rosgraph_msgs/msg/Clock",
                    T["rosgraph_msgs/msg/Clock"](clock=w.header(stamp, "").stamp), stamp)
            w.write("/tf", TFMESSAGE, T[TFMESSAGE](transforms=[w.transform(
                stamp, options.world_frame, options.base_frame, T_W_base)]), stamp)
            raw = {"x": scan.points[:, 0], "y": scan.points[:, 1], "z": scan.points[:, 2],
                   "intensity": scan.remission}
            w.write(options.raw_topic, POINTCLOUD2, w.cloud(stamp, options.sensor_frame, raw),
                    stamp)
            evidence = scan_evidence(scan, classes, options, learned)
            columns = {"x": scan.points[:, 0], "y": scan.points[:, 1], "z": scan.points[:, 2],
                       "evidence": evidence}
            w.write(options.evidence_topic, POINTCLOUD2, w.cloud(stamp, options.sensor_frame,
                                                                 columns), stamp)
            last = (raw, columns)
            bar.tick()
        outside = None
        if options.outside_buffer and last is not None:
            outside = stamps[-1] + 1_000_000_000  # 1 s after the last /tf: outside the buffer
            w.write("/clock", "rosgraph_msgs/msg/Clock",
                    T["rosgraph_msgs/msg/Clock"](clock=w.header(outside, "").stamp), outside)
            raw, columns = last
            w.write(options.raw_topic, POINTCLOUD2, w.cloud(outside, options.sensor_frame, raw),
                    outside)
            w.write(options.evidence_topic, POINTCLOUD2,
                    w.cloud(outside, options.sensor_frame, columns), outside)
    finally:
        w.close()
        bar.close()
    return {"bag": str(out), "format": "ROS 2 bag (" + options.storage + ")" if options.ros2
            else "ROS 1 bag", "scans": n, "stamps_ns": stamps, "outside_buffer_stamp_ns": outside,
            "topics": [options.raw_topic, options.evidence_topic, "/tf", "/tf_static", "/clock",
                       "/evidence_source"], "evidence_source": source}


# --- command line ---------------------------------------------------------------------------
def _classes(path):
    return _core.ClassTable.load(str(path))


def _add_map_arguments(p):
    p.add_argument("bag", help="a ROS 1 .bag file or a ROS 2 bag directory (MCAP or sqlite3)")
    p.add_argument("--classes", required=True, help="class table YAML (config/classes_*.yaml)")
    p.add_argument("--frame", default="map", help="map frame: clouds are placed by the TF from "
                   "their frame to this one at their stamp (default map)")
    p.add_argument("--out", required=True, help="output directory (map.ot, summary, pictures)")
    p.add_argument("--topic", default=None,
                   help="PointCloud2 topic (needed when the bag has several)")
    p.add_argument("--calibration", default=None,
                   help="a file written by `evidential_octomap calibrate`: the read-out cap and "
                   "the error model of the map's error_probability (docs/calibration.md)")
    p.add_argument("--input", default="auto", choices=pointcloud2.INPUTS,
                   help="semantic field to read (default auto: the first present of evidence, "
                   "alpha, logits, probabilities, label)")
    p.add_argument("--label-magnitude", type=float, default=_core.EVIDENCE_MAGNITUDE,
                   help="evidence of a `label` field's class (default 20)")
    p.add_argument("--raw-labels", action="store_true",
                   help="`label` holds raw dataset ids (mapped by the class table)")
    p.add_argument("--logit-transform", default="softmax", choices=("softmax", "exp", "softplus"))
    p.add_argument("--probability-magnitude", type=float, default=_core.EVIDENCE_MAGNITUDE)
    p.add_argument("--model", default=None,
                   help="for clouds without a semantic field: 'learned' (the bundled learned "
                   "evidence head; needs --predictions) or your own callable "
                   "'file.py:function' / 'module:function' (points, fields) -> (N, C) evidence")
    p.add_argument("--learned-model", default=None,
                   help="model file of --model learned (default: learned/<dataset>.model "
                   "beside the class table)")
    p.add_argument("--predictions", default=None,
                   help="--model learned: a SemanticKITTI-layout directory whose predictions/ "
                   "stand in for the segmentation network (looked up by the cloud's content)")
    p.add_argument("--resolution", type=float, default=0.2, help="voxel size [m] (default 0.2)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="a SemanticConfig parameter, e.g. --set rule=sbki --set max_range=50")
    p.add_argument("--max-clouds", type=int, default=None, help="map only the first N clouds")
    p.add_argument("--no-render", action="store_true", help="skip the PNG pictures")
    p.add_argument("--foxglove", action="store_true",
                   help="serve the map live to Foxglove (WebSocket on 127.0.0.1)")
    p.add_argument("--port", type=int, default=8765, help="Foxglove WebSocket port (default 8765)")
    p.add_argument("--views", default="class,uncertainty,conflict",
                   help="voxel views to publish, of class, uncertainty, conflict (default all; "
                   "each is a topic /map/voxels/<view> to choose in Foxglove)")
    p.add_argument("--mcap-views", default=None, metavar="FILE",
                   help="also write the Foxglove views to this MCAP for later viewing")
    p.add_argument("--view-period", type=float, default=2.0,
                   help="seconds between two published map views (default 2)")
    p.add_argument("--keep-serving", type=float, default=0.0, metavar="S",
                   help="with --foxglove: keep serving S seconds after mapping (-1: until Ctrl-C)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")


def _add_write_arguments(p):
    p.add_argument("data", help="SemanticKITTI-layout directory (velodyne/, predictions/, "
                   "poses.txt, calib.txt, ...)")
    p.add_argument("out", help="the bag: a .bag file (--ros1) or a directory (--ros2)")
    which = p.add_mutually_exclusive_group(required=True)
    which.add_argument("--ros1", action="store_true", help="write a ROS 1 bag")
    which.add_argument("--ros2", action="store_true", help="write a ROS 2 bag")
    p.add_argument("--storage", default="mcap", choices=("mcap", "sqlite3"),
                   help="ROS 2 storage (default mcap)")
    p.add_argument("--classes", required=True, help="class table YAML")
    p.add_argument("--scans", type=int, default=None, help="only the first N scans")
    p.add_argument("--evidence", default="onehot", choices=("onehot", "knn-vote", "file",
                                                           "learned"),
                   help="evidence of the evidence topic (default onehot, derived, no calibration)")
    p.add_argument("-E", "--evidence-magnitude", type=float, default=_core.EVIDENCE_MAGNITUDE)
    p.add_argument("--learned-model", default=None)
    p.add_argument("--rate", type=float, default=10.0, help="scans per second (default 10)")
    p.add_argument("--outside-buffer", action="store_true",
                   help="add one cloud stamped 1 s after the last /tf (outside the TF buffer)")
    p.add_argument("--world-frame", default="map")
    p.add_argument("--base-frame", default="base_link")
    p.add_argument("--sensor-frame", default="velodyne")
    p.add_argument("--raw-topic", default="/velodyne_points")
    p.add_argument("--evidence-topic", default="/velodyne_points/evidence")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")


def make_model(args, classes):
    if args.model is None:
        return None
    if args.model == "learned":
        if not args.predictions:
            raise SystemExit("--model learned needs --predictions DIR: the bundled data ships a "
                             "network's hard predictions, not the network")
        path = args.learned_model or default_learned_model(args.classes, classes)
        return LearnedEvidence(path, DatasetPredictions(args.predictions, classes))
    return load_callable(args.model)


def note_if_uncalibrated(result: BagMap) -> None:
    """Says once, on stderr, that a map of network evidence read without a calibration file has
    an uncalibrated error probability, and how to fit one."""
    s = result.summary
    derived = "derived" in (s["evidence_declared"] or "")
    network = any(not src.startswith(("label", "none")) for src in s["evidence_sources"])
    if result.tree.calibrated or derived or not network:
        return
    print(f"note: {_core.UNCALIBRATED_NOTE} (--calibration FILE)", file=sys.stderr)


def run_map(args) -> int:
    classes = _classes(args.classes)
    options = MapOptions(frame=args.frame, topic=args.topic, resolution=args.resolution,
                         config=config_overrides(args.set), input=args.input,
                         label_magnitude=args.label_magnitude,
                         logit_transform=args.logit_transform,
                         probability_magnitude=args.probability_magnitude,
                         raw_labels=args.raw_labels, max_clouds=args.max_clouds,
                         calibration=args.calibration)
    model = make_model(args, classes)
    view = None
    if args.foxglove or args.mcap_views:
        from .foxglove_view import FoxgloveView
        view = FoxgloveView(classes, frame=args.frame, serve=args.foxglove, port=args.port,
                            mcap=args.mcap_views, period=args.view_period,
                            views=tuple(v.strip() for v in args.views.split(",") if v.strip()))
        if args.foxglove:
            print(f"foxglove: open ws://127.0.0.1:{view.port} in Foxglove (Open connection -> "
                  "Foxglove WebSocket)", file=sys.stderr)
    try:
        result = map_bag(args.bag, classes, options, model, view, progress=not args.quiet)
        written = write_outputs(result, classes, args.out, render=not args.no_render)
        s = result.summary
        print(f"mapped {s['scans_mapped']} of {s['clouds']} clouds in {s['seconds']['total']:.1f} s"
              f" ({s['scans_per_s']:.2f} scans/s); {len(s['dropped'])} dropped")
        for d in s["dropped"]:
            print(f"  dropped cloud {d['index']} ({d['stamp_ns'] / 1e9:.3f} s): {d['reason']}")
        print(f"wrote {args.out}/{{{','.join(written)}}}")
        note_if_uncalibrated(result)
        if view is not None and args.foxglove and args.keep_serving:
            print("foxglove: serving the final map" + (" until Ctrl-C" if args.keep_serving < 0
                  else f" for {args.keep_serving:g} s"), file=sys.stderr)
            view.close_mcap()  # the MCAP holds the mapping run; serving goes on alone
            end = time.monotonic() + (float("inf") if args.keep_serving < 0 else args.keep_serving)
            try:
                while time.monotonic() < end:  # re-published so that late clients see the map
                    time.sleep(max(0.0, min(max(args.view_period, 1.0), end - time.monotonic())))
                    view.publish(result.tree)
            except KeyboardInterrupt:
                pass
    finally:
        if view is not None:
            view.close()
    return 0


def run_write(args) -> int:
    classes = _classes(args.classes)
    options = WriteOptions(ros2=args.ros2, storage=args.storage, scans=args.scans,
                           evidence=args.evidence, magnitude=args.evidence_magnitude,
                           learned_model=args.learned_model, rate=args.rate,
                           outside_buffer=args.outside_buffer, world_frame=args.world_frame,
                           base_frame=args.base_frame, sensor_frame=args.sensor_frame,
                           raw_topic=args.raw_topic, evidence_topic=args.evidence_topic)
    info = write_bag(args.data, args.out, classes, options, args.classes,
                     progress=not args.quiet)
    print(f"wrote {info['format']} {info['bag']}: {info['scans']} scans"
          + (" + 1 cloud outside the TF buffer" if info["outside_buffer_stamp_ns"] else "")
          + f"; topics {', '.join(info['topics'])}; evidence {info['evidence_source']}")
    return 0


def main(argv: Optional[Sequence[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="python -m evidential_octomap.bag", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True)
    _add_map_arguments(sub.add_parser("map", help="map a ROS 1 or ROS 2 bag"))
    _add_write_arguments(sub.add_parser("write", help="write a SemanticKITTI-layout directory "
                                        "as a ROS 1 or ROS 2 bag"))
    args = p.parse_args(argv)
    try:
        return run_map(args) if args.command == "map" else run_write(args)
    except (FileNotFoundError, FileExistsError, ValueError, RuntimeError) as e:
        print(f"evidential_octomap.bag: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
