"""Live Foxglove views of a map while it is built (foxglove-sdk), and an MCAP of the same views.

    view = FoxgloveView(classes, frame="map", port=8765)       # ws://127.0.0.1:8765
    for points_S, evidence, T_W_S, stamp in scans:
        tree.insert_scan(points_S, evidence, pose=T_W_S)
        view.update(tree, points_S, T_W_S, stamp)              # rate-limited map, every cloud
    view.publish(tree)                                          # the map now
    view.close()

Topics (Foxglove schemas, protobuf):

* ``/map/voxels/class``, ``/map/voxels/uncertainty``, ``/map/voxels/conflict`` (SceneUpdate):
  the occupied leaves as cubes of their size, coloured by class (the class table's colours, grey
  without evidence), by uncertainty (the probability that the label is wrong, 1 - max p) or by
  conflict (dark blue 0 -> yellow 1); choose the view by
  the topic in the 3D panel. One entity ``voxels`` per topic, replaced at each publication.
* ``/map/cloud`` (PointCloud): the current cloud in the map frame, with its class
  (argmax of the evidence) as a field to colour by.
* ``/tf`` (FrameTransform): map frame -> the cloud's frame at the cloud's stamp (the sensor pose).

The cubes are encoded straight from the numpy arrays of ``tree.leaves`` (one vectorised protobuf
writer, identical bytes to the SDK's own SceneUpdate for the same cubes: see the tests), since
building one Python object per voxel would cost about 7 us a voxel. The map views are published
at most every ``period`` seconds of wall time and at the end, and only on the topics someone
receives (a subscribed client or the MCAP), so a large map does not slow mapping down and nothing
is computed while nobody watches; the cloud and the pose go out with every cloud. ``max_voxels`` bounds a publication (the
voxels nearest the sensor are kept, and the entity's metadata says how many were left out).
"""
from __future__ import annotations

import threading
import time
from typing import Optional

import numpy as np

VIEWS = ("class", "uncertainty", "conflict")


# --- protobuf, vectorised -------------------------------------------------------------------
def _varint(n: int) -> bytes:
    out = bytearray()
    while True:
        b = n & 0x7F
        n >>= 7
        if n:
            out.append(b | 0x80)
        else:
            out.append(b)
            return bytes(out)


def _key(field: int, wire: int) -> bytes:
    return _varint((field << 3) | wire)


def _len_field(field: int, payload: bytes) -> bytes:
    return _key(field, 2) + _varint(len(payload)) + payload


# One cube: CubePrimitive{pose=1{position=1{x,y,z}, orientation=2{w=4}}, size=2{x,y,z},
# color=3{r,g,b,a}}, every double written (fixed64), so each cube has the same length.
_VEC3 = [("k1", "u1"), ("x", "<f8"), ("k2", "u1"), ("y", "<f8"), ("k3", "u1"), ("z", "<f8")]
_CUBE = np.dtype(
    [("cube_key", "u1"), ("cube_len", "u1"),
     ("pose_key", "u1"), ("pose_len", "u1"),
     ("pos_key", "u1"), ("pos_len", "u1")] + [("p" + n, t) for n, t in _VEC3] +
    [("ori_key", "u1"), ("ori_len", "u1"), ("w_key", "u1"), ("w", "<f8"),
     ("size_key", "u1"), ("size_len", "u1")] + [("s" + n, t) for n, t in _VEC3] +
    [("color_key", "u1"), ("color_len", "u1"),
     ("r_key", "u1"), ("r", "<f8"), ("g_key", "u1"), ("g", "<f8"),
     ("b_key", "u1"), ("b", "<f8"), ("a_key", "u1"), ("a", "<f8")])
_VEC3_LEN = 27
_POSE_LEN = 2 + _VEC3_LEN + 2 + 9
_CUBE_LEN = 2 + _POSE_LEN + 2 + _VEC3_LEN + 2 + 36
assert _CUBE.itemsize == 2 + _CUBE_LEN and _CUBE_LEN < 128


def encode_cubes(centers, sizes, rgba) -> bytes:
    """The ``cubes`` (field 8) of a SceneEntity: (M, 3) centres, (M,) edge lengths, (M, 4)
    colours in [0, 1]."""
    m = len(sizes)
    a = np.empty(m, dtype=_CUBE)
    a["cube_key"], a["cube_len"] = 0x42, _CUBE_LEN           # SceneEntity.cubes = 8
    a["pose_key"], a["pose_len"] = 0x0A, _POSE_LEN           # CubePrimitive.pose = 1
    a["pos_key"], a["pos_len"] = 0x0A, _VEC3_LEN             # Pose.position = 1
    a["ori_key"], a["ori_len"] = 0x12, 9                     # Pose.orientation = 2
    a["w_key"], a["w"] = 0x21, 1.0                           # Quaternion.w = 4
    a["size_key"], a["size_len"] = 0x12, _VEC3_LEN           # CubePrimitive.size = 2
    a["color_key"], a["color_len"] = 0x1A, 36                # CubePrimitive.color = 3
    for prefix, values in (("p", centers), ("s", np.repeat(np.asarray(sizes)[:, None], 3, 1))):
        a[prefix + "k1"], a[prefix + "k2"], a[prefix + "k3"] = 0x09, 0x11, 0x19
        a[prefix + "x"], a[prefix + "y"], a[prefix + "z"] = values[:, 0], values[:, 1], values[:, 2]
    a["r_key"], a["g_key"], a["b_key"], a["a_key"] = 0x09, 0x11, 0x19, 0x21
    a["r"], a["g"], a["b"], a["a"] = rgba[:, 0], rgba[:, 1], rgba[:, 2], rgba[:, 3]
    return a.tobytes()


def encode_scene_update(frame_id: str, entity_id: str, stamp_ns: int, cubes: bytes,
                        metadata: Optional[dict] = None) -> bytes:
    """SceneUpdate{entities=2: [SceneEntity{timestamp=1, frame_id=2, id=3, metadata=6, cubes}]}."""
    sec, nsec = divmod(int(stamp_ns), 1_000_000_000)
    ts = b""
    if sec:
        ts += _key(1, 0) + _varint(sec)
    if nsec:
        ts += _key(2, 0) + _varint(nsec)
    entity = _len_field(1, ts) + _len_field(2, frame_id.encode()) + _len_field(3, entity_id.encode())
    for k, v in (metadata or {}).items():
        entity += _len_field(6, _len_field(1, k.encode()) + _len_field(2, str(v).encode()))
    entity += cubes
    return _len_field(2, entity)


# --- colours --------------------------------------------------------------------------------
def ramp(values) -> np.ndarray:
    """(M, 3) colours in [0, 1] of values in [0, 1]: dark blue -> teal -> yellow."""
    stops = np.array([[0.18, 0.0, 0.33], [0.13, 0.57, 0.55], [0.99, 0.91, 0.14]])
    v = np.clip(np.nan_to_num(np.asarray(values, dtype=np.float64), nan=1.0), 0.0, 1.0) * 2
    i = np.minimum(v.astype(int), 1)
    f = (v - i)[:, None]
    return stops[i] * (1 - f) + stops[i + 1] * f


def voxel_colors(leaves, classes, view: str) -> np.ndarray:
    """(M, 4) RGBA of each leaf in a view: class colours (grey without evidence), uncertainty or
    conflict."""
    m = len(leaves.sizes)
    rgba = np.ones((m, 4))
    if view == "class":
        palette = np.vstack([np.asarray(classes.colors, dtype=np.float64) / 255.0,
                             [[0.6, 0.6, 0.6]]])
        labels = np.where(leaves.labels >= 0, leaves.labels, len(palette) - 1)
        rgba[:, :3] = palette[labels]
    elif view == "uncertainty":  # the default uncertainty: P(label wrong) = 1 - max p
        rgba[:, :3] = ramp(leaves.error_probability)
    elif view == "conflict":
        rgba[:, :3] = ramp(leaves.conflict)
    else:
        raise ValueError(f"view must be one of {', '.join(VIEWS)}, got '{view}'")
    return rgba


# --- the view -------------------------------------------------------------------------------
class FoxgloveView:
    """Publishes a map's views to a Foxglove WebSocket server and/or an MCAP file."""

    def __init__(self, classes, frame: str = "map", serve: bool = True, host: str = "127.0.0.1",
                 port: int = 8765, mcap: Optional[str] = None, period: float = 2.0,
                 views=VIEWS, max_voxels: int = 1_000_000):
        import foxglove
        from foxglove import messages
        unknown = [v for v in views if v not in VIEWS]
        if unknown or not views:
            raise ValueError(f"views must be some of {', '.join(VIEWS)}, got {list(views)}")
        self.classes, self.frame, self.period, self.max_voxels = classes, frame, period, max_voxels
        self.views = tuple(views)
        self._m = messages
        self.context = foxglove.Context()
        schema = messages.SceneUpdate.get_schema()
        self._voxels = {v: foxglove.Channel(f"/map/voxels/{v}", schema=schema,
                                            message_encoding="protobuf", context=self.context)
                        for v in self.views}
        self._cloud = foxglove.channels.PointCloudChannel("/map/cloud", context=self.context)
        self._tf = foxglove.channels.FrameTransformChannel("/tf", context=self.context)
        self.server = None
        self.mcap = None
        if mcap:
            self.mcap = foxglove.open_mcap(mcap, allow_overwrite=True, context=self.context)
        if serve:
            self.server = foxglove.start_server(name="evidential_octomap", host=host, port=port,
                                                context=self.context)
        self._last = -float("inf")
        self._origin = np.zeros(3)
        self._stamp = 0
        self.published = 0          # map publications
        self.last_voxels = 0        # cubes in the last one
        self.seconds = 0.0          # time the caller spent here (what slows mapping down)
        # Encoding and sending run on a worker thread, beside the next insert (which releases
        # the GIL); the newest job of each kind waits, an older one not yet started is replaced.
        self._pending = {}
        self._busy = False
        self._closing = False
        self._cv = threading.Condition()
        self._worker = threading.Thread(target=self._run, name="foxglove-view", daemon=True)
        self._worker.start()

    @property
    def port(self) -> Optional[int]:
        return self.server.port if self.server is not None else None

    def update(self, tree, points_S, pose, stamp_ns: int, sensor_frame: str = "sensor",
               evidence=None):
        """After each inserted cloud: the cloud and the sensor pose; the map when `period` has
        passed since the last map publication."""
        t0 = time.monotonic()
        self._stamp, self._origin = int(stamp_ns), np.asarray(pose)[:3, 3].copy()
        if self._tf.has_sinks() or self._cloud.has_sinks():
            self._submit("cloud", (np.asarray(points_S), np.array(pose, dtype=np.float64),
                                   int(stamp_ns), sensor_frame, evidence))
        self.seconds += time.monotonic() - t0
        if time.monotonic() - self._last >= self.period:
            self.publish(tree, stamp_ns)

    def finish(self, tree):
        """The final map, sent before this returns."""
        self.publish(tree, self._stamp)
        self.flush()

    def publish(self, tree, stamp_ns: Optional[int] = None) -> int:
        """The map now, on every view someone receives (a subscribed client, the MCAP); returns
        the number of cubes in each (0: nobody receives any view, nothing was done). The leaves
        are read here (the tree must not change meanwhile); encoding and sending run on the
        worker (``flush()`` waits for it)."""
        channels = {v: c for v, c in self._voxels.items() if c.has_sinks()}
        if not channels:
            return 0
        t0 = time.monotonic()
        stamp = self._stamp if stamp_ns is None else int(stamp_ns)
        leaves = tree.leaves(occupied_only=True)
        n = len(leaves.sizes)
        keep = None
        if n > self.max_voxels:  # the nearest to the sensor
            d = np.linalg.norm(leaves.centers - self._origin, axis=1)
            keep = np.argpartition(d, self.max_voxels)[: self.max_voxels]
        count = n if keep is None else len(keep)
        meta = {"voxels": count, "occupied_leaves": n, "left_out": n - count,
                "resolution": tree.resolution, "rule": tree.rule}
        self._submit("map", (leaves, keep, channels, stamp, meta))
        self._last = time.monotonic()
        self.published += 1
        self.last_voxels = count
        self.seconds += time.monotonic() - t0
        return count

    def flush(self):
        """Waits until every submitted view has been sent."""
        with self._cv:
            while self._pending or self._busy:
                self._cv.wait()

    # --- worker
    def _submit(self, kind, job):
        with self._cv:
            self._pending[kind] = job
            self._cv.notify_all()

    def _run(self):
        while True:
            with self._cv:
                while not self._pending and not self._closing:
                    self._cv.wait()
                if not self._pending:
                    return
                kind = "map" if "map" in self._pending else next(iter(self._pending))
                job = self._pending.pop(kind)
                self._busy = True
            try:
                if kind == "map":
                    self._send_map(*job)
                else:
                    points_S, pose, stamp, sensor_frame, evidence = job
                    if self._tf.has_sinks():
                        self._publish_pose(pose, stamp, sensor_frame)
                    if self._cloud.has_sinks():
                        self._publish_cloud(points_S, pose, stamp, evidence)
            finally:
                with self._cv:
                    self._busy = False
                    self._cv.notify_all()

    def _send_map(self, leaves, keep, channels, stamp, meta):
        centers = leaves.centers.astype(np.float64)
        sizes = leaves.sizes.astype(np.float64)
        if keep is not None:
            centers, sizes = centers[keep], sizes[keep]
        for view, channel in channels.items():
            rgba = voxel_colors(leaves, self.classes, view)
            if keep is not None:
                rgba = rgba[keep]
            data = encode_scene_update(self.frame, "voxels", stamp,
                                       encode_cubes(centers, sizes, rgba), {**meta, "view": view})
            channel.log(data, log_time=stamp or None)

    def _publish_pose(self, pose, stamp_ns, sensor_frame):
        from .tf_buffer import quaternion
        m = self._m
        x, y, z, w = quaternion(np.asarray(pose)[:3, :3])
        t = np.asarray(pose)[:3, 3]
        sec, nsec = divmod(int(stamp_ns), 1_000_000_000)
        self._tf.log(m.FrameTransform(
            timestamp=m.Timestamp(sec=sec, nsec=nsec), parent_frame_id=self.frame,
            child_frame_id=sensor_frame,
            translation=m.Vector3(x=float(t[0]), y=float(t[1]), z=float(t[2])),
            rotation=m.Quaternion(x=float(x), y=float(y), z=float(z), w=float(w))),
            log_time=int(stamp_ns) or None)

    def _publish_cloud(self, points_S, pose, stamp_ns, evidence):
        m = self._m
        T = np.asarray(pose, dtype=np.float64)
        p = np.asarray(points_S, dtype=np.float64) @ T[:3, :3].T + T[:3, 3]
        label = (np.argmax(evidence, axis=1).astype(np.float32) if evidence is not None
                 else np.zeros(len(p), dtype=np.float32))
        data = np.empty(len(p), dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"),
                                       ("label", "<f4")])
        data["x"], data["y"], data["z"], data["label"] = p[:, 0], p[:, 1], p[:, 2], label
        f32 = m.PackedElementFieldNumericType.Float32
        sec, nsec = divmod(int(stamp_ns), 1_000_000_000)
        self._cloud.log(m.PointCloud(
            timestamp=m.Timestamp(sec=sec, nsec=nsec), frame_id=self.frame,
            pose=m.Pose(position=m.Vector3(x=0, y=0, z=0),
                        orientation=m.Quaternion(x=0, y=0, z=0, w=1)),
            point_stride=16,
            fields=[m.PackedElementField(name=n, offset=4 * i, type=f32)
                    for i, n in enumerate(("x", "y", "z", "label"))],
            data=data.tobytes()), log_time=int(stamp_ns) or None)

    def close_mcap(self):
        self.flush()
        if self.mcap is not None:
            self.mcap.close()
            self.mcap = None

    def close(self):
        self.flush()
        with self._cv:
            self._closing = True
            self._cv.notify_all()
        self._worker.join()
        if self.server is not None:
            self.server.stop()
            self.server = None
        self.close_mcap()
