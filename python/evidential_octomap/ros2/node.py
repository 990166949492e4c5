"""The ROS 2 mapping node: converts messages and wires them to the core and to the ROS-free
modules beside it (field rules: pointcloud2.py; TF: tf_wait.py; parameters and their checks:
parameters.py; views: views.py, projection.py; status: status.py). The insert runs on its own
thread behind a latest-only queue, as the ROS 1 node's: the executor reads each cloud and waits
for its transform, and keeps taking TF, parameters and service calls while a scan is inserted."""
import os
import sys
import threading
import time
from pathlib import Path
from typing import NamedTuple, Optional

import numpy as np

from .. import _core, bundled_class_table, pointcloud2
from ..models import load_callable
from . import parameters, projection, views
from .latest_queue import LatestQueue
from .status import MALFORMED, NO_SEMANTICS, NO_TRANSFORM, QUEUE_FULL, REFUSED, Status
from .tf_wait import TfError, WaitingTf

try:
    import rclpy
    from geometry_msgs.msg import Point
    from nav_msgs.msg import OccupancyGrid
    from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
    from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
    from rclpy.event_handler import SubscriptionEventCallbacks
    from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
    from rclpy.node import Node
    from rclpy.qos import (DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy,
                           qos_profile_sensor_data)
    from sensor_msgs.msg import PointCloud2, PointField
    from std_msgs.msg import ColorRGBA, String
    from std_srvs.srv import Trigger
    from visualization_msgs.msg import Marker, MarkerArray
except ImportError as e:  # pragma: no cover - said once, plainly
    raise SystemExit(f"evidential_octomap.ros2 needs the ROS 2 wheels ({e}): pip install "
                     "\".[ros2]\"") from None
try:
    from evidential_octomap_msgs.srv import QueryMap, SaveMap
    from tf2_msgs.msg import TFMessage
except ImportError as e:  # pragma: no cover
    raise SystemExit(f"evidential_octomap.ros2 needs interfaces no wheel provides ({e}): pip "
                     "install ./python/ros2_interfaces/tf2_msgs "
                     "./python/ros2_interfaces/evidential_octomap_msgs (they generate them)") \
        from None

NODE_NAME = "evidential_mapping_node"
# Latched, as the ROS 1 node's map topics: a late subscriber gets the last message.
LATCHED = QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST,
                     reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
TF_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
TF_STATIC_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE,
                           durability=DurabilityPolicy.TRANSIENT_LOCAL)
MARKER_TOPICS = {"class": "occupied_cells_vis_array", "uncertainty": "uncertainty_cells_vis_array",
                 "conflict": "conflict_cells_vis_array"}


class ReadyCloud(NamedTuple):
    """A received cloud, read and with its pose, waiting for the insert."""
    header: object
    points: np.ndarray              # (N, 3) in the cloud's frame
    evidence: Optional[np.ndarray]  # (N, C); None: the `model` gives it, on the insert thread
    fields: dict                    # every field of the points, for the model
    pose: np.ndarray                # 4 x 4, the cloud's frame -> frame_id
    source: str                     # which field the evidence came from


def stamp_ns(stamp) -> int:
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def cloud_message(header, columns) -> "PointCloud2":
    fields, step, data = pointcloud2.pack_typed(columns)
    n = len(next(iter(columns.values())))
    msg = PointCloud2(header=header, height=1, width=n, is_bigendian=False, point_step=step,
                      row_step=step * n, is_dense=True)
    msg.fields = [PointField(name=a, offset=o, datatype=d, count=c) for a, o, d, c in fields]
    msg.data = data.tobytes()
    return msg


class MappingNode(Node):
    def __init__(self, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        self.params = parameters.all_parameters()
        self.by_name = {p.name: p for p in self.params}
        for p in self.params:
            constraints = ("one of " + ", ".join(p.choices) if p.choices else
                           p.check[1] if p.check else p.range_text)
            # floats typed dynamically, so that an integer (YAML `2`, `:=1`) is taken as 2.0
            self.declare_parameter(p.name, p.default, ParameterDescriptor(
                description=p.description, read_only=p.read_only,
                additional_constraints=constraints,
                dynamic_typing=isinstance(p.default, float)))
        self.values, reason = {}, ""
        for p in self.params:
            self.values[p.name], why = parameters.coerce(p, self.get_parameter(p.name).value)
            reason = reason or why
        reason = reason or parameters.problem(self.values, self.params)
        if reason:
            raise ValueError(f"parameter refused: {reason}")
        self.status = Status()
        self.lock = threading.Lock()  # the tree: inserts, views, services, autosave
        self.map_size_recorded, self.map_size_walk_s, self.map_size_stale = 0.0, 0.0, False
        self._load_map()
        self.tf = WaitingTf(self.values["tf_cache_time"])
        self.model = load_callable(self.values["model"]) if self.values.get("model") else None
        self.queue = LatestQueue(self.values["insert_queue_size"])
        self.changed = threading.Event()
        self.force_views = threading.Event()
        self.unsaved = False
        self.running = True
        self.view_lock_s = 0.0

        # clouds, TF and services each in their own group, so a burst of clouds never holds
        # up the transforms they wait for, nor a service call
        services, tf_group, clouds = (MutuallyExclusiveCallbackGroup() for _ in range(3))
        cloud_qos = (qos_profile_sensor_data if self.values["cloud_in_qos"] == "sensor_data"
                     else QoSProfile(depth=5, reliability=ReliabilityPolicy.RELIABLE))
        self.create_subscription(PointCloud2, "cloud_in", self._on_cloud, cloud_qos,
                                 callback_group=clouds, event_callbacks=SubscriptionEventCallbacks(
                                     message_lost=self._on_lost))
        self.create_subscription(TFMessage, "/tf", lambda m: self.tf.add_message(m), TF_QOS,
                                 callback_group=tf_group)
        self.create_subscription(TFMessage, "/tf_static",
                                 lambda m: self.tf.add_message(m, static=True), TF_STATIC_QOS,
                                 callback_group=tf_group)
        self.markers = {v: self.create_publisher(MarkerArray, t, LATCHED)
                        for v, t in MARKER_TOPICS.items()}
        self.marker_subscribers = {v: 0 for v in MARKER_TOPICS}
        self.cloud_pub = self.create_publisher(PointCloud2, "semantic_cloud", LATCHED)
        self.grid_pub = self.create_publisher(OccupancyGrid, "projected_map", LATCHED)
        self.status_pub = self.create_publisher(String, "~/status", LATCHED)
        self.create_service(SaveMap, "~/save_map", self._on_save, callback_group=services)
        self.create_service(QueryMap, "~/query", self._on_query, callback_group=services)
        self.create_service(Trigger, "~/reset", self._on_reset, callback_group=services)
        self.create_timer(1.0, self._publish_status, callback_group=services)
        if self.values["autosave_period"] > 0:
            self.create_timer(self.values["autosave_period"], self._autosave,
                              callback_group=services)
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self.foxglove = None
        if self.values["foxglove_port"] >= 0:
            from ..foxglove_view import FoxgloveView
            self.foxglove = FoxgloveView(self.classes, frame=self.values["frame_id"],
                                         port=self.values["foxglove_port"])
            self.get_logger().info(f"foxglove: open ws://127.0.0.1:{self.foxglove.port} in "
                                   "Foxglove (Open connection -> Foxglove WebSocket)")
        self.threads = [threading.Thread(target=self._insert_loop, name="insert", daemon=True),
                        threading.Thread(target=self._view_loop, name="views", daemon=True)]
        for t in self.threads:
            t.start()
        self.force_views.set()
        self.get_logger().info(
            f"mapping {self.classes.num_classes} classes into '{self.values['frame_id']}' at "
            f"{self.tree.resolution} m, rule {self.tree.rule}; cloud_in -> "
            f"{self.resolve_topic_name('cloud_in')}")

    # --- start-up -------------------------------------------------------------------------
    def _load_map(self):
        v = self.values
        self.classes = (_core.ClassTable.load(v["classes"]) if v["classes"]
                        else bundled_class_table("semantickitti"))
        if v["num_classes"] and v["num_classes"] != self.classes.num_classes:
            raise ValueError(f"num_classes = {v['num_classes']} but the class table has "
                             f"{self.classes.num_classes} classes")
        config = parameters.semantic_config(v, self.params)
        self.autosave_path = Path(v["autosave_path"] or Path(os.environ.get(
            "ROS_HOME", Path.home() / ".ros")) / "evidential_octomap" /
            f"{self.get_name()}.autosave.ot")
        start = v["map_file"]
        if v["autosave_period"] > 0 and v["resume_from_autosave"] and self.autosave_path.is_file():
            start = str(self.autosave_path)
            age = time.time() - self.autosave_path.stat().st_mtime
            self.get_logger().info(f"resuming from the autosave {start} ({age:.0f} s old)")
        if start:
            self.tree = _core.EvidentialOcTree.load(start)
            if self.tree.num_classes != self.classes.num_classes:
                raise ValueError(f"{start} has {self.tree.num_classes} classes, the class table "
                                 f"{self.classes.num_classes}")
            self.tree.set_config(config)
            self.tree.movable_classes = self.classes.movable  # not stored in an .ot
        else:
            self.tree = _core.EvidentialOcTree(v["resolution"], self.classes, config)
        self._set_sensor_model(v)
        if v["calibration_file"]:
            self.tree.apply_calibration(_core.read_calibration(v["calibration_file"]))
        self._record_map_size()

    def _set_sensor_model(self, v):
        self.tree.prob_hit = v["sensor_model.hit"]
        self.tree.prob_miss = v["sensor_model.miss"]
        self.tree.clamping_thres_min = v["sensor_model.min"]
        self.tree.clamping_thres_max = v["sensor_model.max"]

    # --- parameters ---------------------------------------------------------------------
    def _on_set_parameters(self, changed):
        values, reason = dict(self.values), ""
        for p in changed:
            if p.name in self.by_name:
                values[p.name], why = parameters.coerce(self.by_name[p.name], p.value)
                reason = reason or why
        reason = reason or parameters.problem(values, self.params)
        if not reason:
            try:
                with self.lock:
                    self.tree.set_config(parameters.semantic_config(values, self.params))
                    self._set_sensor_model(values)
            except (ValueError, RuntimeError) as e:
                reason = str(e)
        names = ", ".join(f"{p.name}={p.value}" for p in changed)
        if reason:
            self.status.event(f"refused {names}: {reason}")
            self.get_logger().warning(f"parameter refused ({names}): {reason}")
            return SetParametersResult(successful=False, reason=reason)
        self.values = values
        self.queue.resize(values["insert_queue_size"])
        self.status.event(f"set {names}")
        return SetParametersResult(successful=True)

    # --- input ----------------------------------------------------------------------------
    def _on_cloud(self, msg):
        """Reception, on the executor (as the ROS 1 node's reception thread): the cloud is read
        and its transform awaited here, so the insert waits for neither. A `model` runs on the
        insert thread, on the newest cloud: here a slow network would hold clouds back in DDS."""
        self.status.received_cloud()
        try:
            ready = self._receive(msg)
        except Exception as e:  # never the executor's end: the cloud is dropped, with why
            return self._drop(MALFORMED, msg.header, f"not read: {type(e).__name__}: {e}")
        if ready is None:
            return
        pushed_out = self.queue.put(ready)
        if pushed_out is not None:
            self._drop(QUEUE_FULL, pushed_out.header, "the insert queue was full "
                       f"(insert_queue_size {self.values['insert_queue_size']}): a newer cloud "
                       "replaced it")

    def _receive(self, msg) -> Optional[ReadyCloud]:
        v = self.values
        t0 = time.monotonic()
        try:
            cloud = pointcloud2.decode(msg, self.classes.num_classes, v["input_type"],
                                       v["label_evidence"], v["logit_transform"],
                                       v["probability_evidence"],
                                       self.classes if v["label_is_raw"] else None)
        except pointcloud2.CloudError as e:
            return self._drop(MALFORMED, msg.header, f"{e}; map unchanged")
        if cloud.evidence is None and self.model is None:
            return self._drop(NO_SEMANTICS, msg.header, "no semantic field (evidence, alpha, "
                              "logits, probabilities or label; fields: "
                              f"{', '.join(f.name for f in msg.fields)}) and no `model`")
        t_read = time.monotonic()
        try:
            pose = self.tf.lookup(v["frame_id"], msg.header.frame_id, stamp_ns(msg.header.stamp),
                                  v["transform_timeout"])
        except TfError as e:
            return self._drop(NO_TRANSFORM, msg.header, str(e))
        self.status.received_stages(t_read - t0, time.monotonic() - t_read)
        return ReadyCloud(msg.header, cloud.points, cloud.evidence, cloud.fields, pose,
                          cloud.source)

    def _on_lost(self, info):
        """Clouds DDS lost before the node saw them (its reader's history overflowed, or
        fragments of a best-effort cloud went missing), as the middleware counts them."""
        self.status.lost_in_dds(info.total_count)
        self.get_logger().warning(f"{info.total_count_change} cloud(s) lost in DDS before "
                                  f"reaching the node ({info.total_count} in all)",
                                  throttle_duration_sec=2.0)

    def _drop(self, kind, header, reason):
        frame = header.frame_id
        text = f"cloud dropped (frame {frame}, {stamp_ns(header.stamp) / 1e9:.3f} s): {reason}"
        self.status.drop(kind, text, stamp_ns(header.stamp), frame)
        self.get_logger().warning(text, throttle_duration_sec=2.0)

    def _insert_loop(self):
        while self.running:
            ready = self.queue.get(timeout=0.2)
            if ready is not None:
                try:
                    self._insert(ready)
                except Exception as e:  # the insert thread lives on
                    self._drop(REFUSED, ready.header, f"not inserted: {type(e).__name__}: {e}")
            elif self.map_size_stale:  # no cloud for a moment: the status catches up
                with self.lock:
                    self._record_map_size()

    def _map_size_after_insert(self):
        """The map's size walks every leaf (~30 ms at 1.4 M leaves), so after an insert it is
        recorded in at most 2 % of the time, and with clouds waiting at most once a second; the
        idle loop records it otherwise (as the ROS 1 node does)."""
        walks_apart = 50.0 * self.map_size_walk_s
        due = walks_apart if len(self.queue) == 0 else max(1.0, walks_apart)
        if time.monotonic() - self.map_size_recorded >= due:
            self._record_map_size()
        else:
            self.map_size_stale = True

    def _record_map_size(self):  # under self.lock
        t0 = time.monotonic()
        self.status.set_map(self.tree)
        self.map_size_recorded = time.monotonic()
        self.map_size_walk_s = self.map_size_recorded - t0
        self.map_size_stale = False

    def _insert(self, ready: ReadyCloud):
        evidence = ready.evidence
        if evidence is None:
            try:
                evidence = np.asarray(self.model(ready.points, ready.fields), dtype=np.float32)
            except Exception as e:  # a user's model: report, keep mapping
                return self._drop(REFUSED, ready.header,
                                  f"model failed: {type(e).__name__}: {e}")
        t_wait = time.monotonic()
        try:
            with self.lock:
                t0 = time.monotonic()
                self.tree.insert_scan(ready.points, evidence, pose=ready.pose)
                t_inserted = time.monotonic()
                self._map_size_after_insert()
                if self.foxglove is not None:  # the cloud, the pose, the map when due
                    self.foxglove.update(self.tree, ready.points, ready.pose,
                                         stamp_ns(ready.header.stamp), ready.header.frame_id,
                                         evidence)
        except ValueError as e:
            return self._drop(REFUSED, ready.header, f"evidence refused: {e}; map unchanged")
        self.status.inserted_cloud(len(ready.points), t0 - t_wait, t_inserted - t0)
        if not self.tree.calibrated and not ready.source.startswith(("label", "none")):
            self.get_logger().warning(f"{_core.UNCALIBRATED_NOTE} (calibration_file)",
                                      once=True)
        self.unsaved = True
        self.changed.set()

    def _on_query(self, request, response):
        """The ROS 1 node's QueryMap: points in frame_id -> label (-1 unknown or no evidence),
        class name, u, conflict, occupancy (1 occupied, 0 free, -1 unknown: the bindings' query
        has no probability), the beliefs (N x C, row-major) and P(label wrong)."""
        points = np.array([[p.x, p.y, p.z] for p in request.points], dtype=np.float32)
        points = points.reshape(-1, 3)
        with self.lock:
            r = self.tree.query(points)
        names = list(self.classes.names)
        response.labels = r.labels.tolist()
        response.class_names = [names[c] if c >= 0 else "" for c in r.labels.tolist()]
        response.uncertainties = r.uncertainty.astype(np.float32).tolist()
        response.conflicts = r.conflict.astype(np.float32).tolist()
        response.occupancy = np.where(r.known, r.occupied.astype(np.float32), -1.0).tolist()
        response.beliefs = np.asarray(r.belief, np.float32).reshape(-1).tolist()
        response.error_probabilities = r.error_probability.astype(np.float32).tolist()
        response.num_classes = self.classes.num_classes
        return response

    # --- outputs --------------------------------------------------------------------------
    def _view_loop(self):
        last = foxglove_last = 0.0
        while self.running:
            if self.foxglove is not None and time.monotonic() - foxglove_last >= 2.0:
                foxglove_last = time.monotonic()  # for Foxglove clients that joined since
                with self.lock:
                    self.foxglove.publish(self.tree)
            rate = self.values["publish_rate"]
            # the views hold the map lock while they copy the leaves: at most a fifth of the time
            period = max(1.0 / rate if rate > 0 else 0.0, 4.0 * self.view_lock_s)
            try:
                new_subscriber = any(self.markers[v].get_subscription_count() > n
                                     for v, n in self.marker_subscribers.items())
            except Exception:
                if self.context.ok():
                    raise
                return  # the context is shut down (Ctrl-C, SIGTERM): the node is stopping
            due = self.changed.is_set() and time.monotonic() - last >= period
            if due or new_subscriber or self.force_views.is_set():
                self.changed.clear()
                self.force_views.clear()
                last = time.monotonic()
                try:
                    self._publish_views()
                except Exception as e:  # a view must never stop the mapper
                    self.get_logger().error(f"views not published: {type(e).__name__}: {e}")
            time.sleep(0.05)

    def _publish_views(self):
        v = self.values
        t0 = time.monotonic()
        band = (v["occupancy_min_z"], v["occupancy_max_z"])
        with self.lock:  # only the copies out: the insert waits for nothing else
            occupied = self.tree.leaves(occupied_only=True)
            grid = projection.project(self.tree, *band)
        self.view_lock_s = time.monotonic() - t0
        self.status.views(self.view_lock_s)
        leaves = views.in_band(occupied, *band)
        header = self._header()
        self.cloud_pub.publish(cloud_message(header, views.cloud_columns(leaves, self.classes)))
        self.grid_pub.publish(self._grid_message(header, grid))
        points = None
        for view, pub in self.markers.items():
            n = pub.get_subscription_count()
            self.marker_subscribers[view] = n
            if n == 0:  # markers cost ~1 s per 300k voxels in Python: only for someone
                continue
            if points is None:
                points = [Point(x=x, y=y, z=z) for x, y, z in leaves.centers.tolist()]
            pub.publish(self._markers(header, leaves, view, points))

    def _header(self):
        from std_msgs.msg import Header
        return Header(stamp=self.get_clock().now().to_msg(), frame_id=self.values["frame_id"])

    def _markers(self, header, leaves, view, points):
        palette, index = views.colours(leaves, self.classes, view)
        colours = [ColorRGBA(r=r, g=g, b=b, a=a) for r, g, b, a in palette.tolist()]
        out = MarkerArray(markers=[Marker(header=header, ns=view, action=Marker.DELETEALL)])
        for i, (size, members) in enumerate(views.by_size(leaves)):
            m = Marker(header=header, ns=view, id=i, type=Marker.CUBE_LIST, action=Marker.ADD)
            m.pose.orientation.w = 1.0
            m.scale.x = m.scale.y = m.scale.z = size
            m.points = [points[j] for j in members.tolist()]
            m.colors = [colours[j] for j in index[members].tolist()]
            out.markers.append(m)
        return out

    def _grid_message(self, header, grid):
        msg = OccupancyGrid(header=header)
        msg.info.resolution = float(grid.resolution)
        msg.info.height, msg.info.width = (int(n) for n in grid.data.shape)
        msg.info.origin.position.x, msg.info.origin.position.y = grid.origin
        msg.info.origin.orientation.w = 1.0
        msg.data = grid.data.reshape(-1).tobytes()
        return msg

    def _publish_status(self):
        self.status_pub.publish(String(data=self.status.to_json(len(self.queue))))

    # --- services -------------------------------------------------------------------------
    def _on_save(self, request, response):
        """SaveMap: the map as .ot (atomic) and its occupancy as .bt beside it; a path ending in
        .bt writes the .bt only (as the ROS 1 node). "" = save_path."""
        path = Path(request.path or self.values["save_path"]).expanduser().resolve()
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            with self.lock:
                if path.suffix != ".bt":
                    self.tree.save(str(path))
                self.tree.save_occupancy(str(path.with_suffix(".bt")))
                leaves = self.tree.num_leaves
            written = ([path] if path.suffix == ".bt" else [path, path.with_suffix(".bt")])
            response.success, response.path = True, str(path)
            response.message = f"wrote {' and '.join(map(str, written))} ({leaves} leaves)"
        except (RuntimeError, OSError) as e:
            response.success, response.message = False, f"map not saved: {e}"
        self.status.event(response.message)
        return response

    def _on_reset(self, request, response):
        with self.lock:
            self.tree.clear()
            self._record_map_size()
        self.force_views.set()
        response.success, response.message = True, "map reset: empty"
        self.status.event(response.message)
        return response

    def _autosave(self):
        if not self.unsaved:
            return
        try:
            self.autosave_path.parent.mkdir(parents=True, exist_ok=True)
            with self.lock:
                self.unsaved = False
                self.tree.save(str(self.autosave_path))
            self.status.event(f"autosaved {self.autosave_path}")
        except (RuntimeError, OSError) as e:
            self.status.event(f"autosave failed: {e}")
            self.get_logger().error(f"autosave failed: {e}")

    def shutdown(self):
        self.running = False
        self.queue.close()
        for t in self.threads:
            t.join(timeout=5)
        if self.foxglove is not None:
            self.foxglove.close()


def _restart_with_sleeping_omp_threads():
    """The core's OpenMP threads sleep while they wait, as launch/mapping.launch sets for the ROS
    1 node: spinning, they took 11 ms CPU an insert from the cores the executor and the rest of
    the robot need, for no gain in wall time. libgomp reads OMP_WAIT_POLICY when it is loaded,
    which the package's import has done by now: hence one restart of the process, in place (the
    same pid). A value the user set is kept."""
    os.environ["OMP_WAIT_POLICY"] = "passive"
    spec = getattr(sys.modules.get("__main__"), "__spec__", None)
    command = ([sys.executable, "-m", spec.name.removesuffix(".__main__")] if spec
               else [sys.executable, sys.argv[0]])  # the console script
    sys.stdout.flush()
    sys.stderr.flush()
    os.execv(sys.executable, command + sys.argv[1:])


def main(argv=None) -> int:
    """Console script and ``python -m evidential_octomap.ros2``; takes --ros-args."""
    if argv is None and "OMP_WAIT_POLICY" not in os.environ:
        _restart_with_sleeping_omp_threads()
    rclpy.init(args=sys.argv if argv is None else argv)
    try:
        node = MappingNode()
    except Exception as e:  # a refused parameter, class table or map file: say it and stop
        print(f"{NODE_NAME}: {type(e).__name__}: {e}" if not isinstance(e, ValueError)
              else f"{NODE_NAME}: {e}", file=sys.stderr)
        rclpy.try_shutdown()
        return 1
    executor = MultiThreadedExecutor(num_threads=3)
    executor.add_node(node)
    try:
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    return 0
