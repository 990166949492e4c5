"""A small TF buffer over /tf and /tf_static, for mapping recorded bags without ROS.

Frames form a tree (each child has one parent, as in tf2). :meth:`TfBuffer.lookup` chains the
transforms from the source frame up to the common ancestor and down to the target frame; every
dynamic (``/tf``) edge is interpolated at the requested stamp (translation linearly, rotation by
slerp, as tf2 does); static (``/tf_static``) edges hold at every time. A stamp outside the
samples of a dynamic edge raises :class:`TfError` naming the frames, the edge and its time range
(tf2 would refuse to extrapolate too). Stamps are integer nanoseconds.

    tf = TfBuffer()
    tf.add("map", "base_link", stamp_ns, (x, y, z), (qx, qy, qz, qw))
    tf.add("base_link", "velodyne", 0, (0, 0, 1.73), (0, 0, 0, 1), static=True)
    T_map_velodyne = tf.lookup("map", "velodyne", stamp_ns)   # 4 x 4, maps velodyne -> map
"""
import bisect
from typing import Dict, List, Tuple

import numpy as np


class TfError(LookupError):
    """No transform between two frames at a stamp (the message says which and why)."""


def seconds(stamp_ns: int) -> str:
    return f"{stamp_ns / 1e9:.9f} s"


def matrix(translation, rotation_xyzw) -> np.ndarray:
    """4 x 4 rigid transform of a translation and a quaternion (x, y, z, w), normalised."""
    x, y, z, w = np.asarray(rotation_xyzw, dtype=np.float64) / np.linalg.norm(rotation_xyzw)
    T = np.eye(4)
    T[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                 [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                 [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    T[:3, 3] = translation
    return T


def quaternion(R) -> Tuple[float, float, float, float]:
    """(x, y, z, w) of a rotation matrix (Shepperd's method, as the dataset player)."""
    r = np.asarray(R, dtype=np.float64)
    t = np.trace(r)
    if t > 0:
        s = np.sqrt(t + 1.0) * 2
        return ((r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s,
                0.25 * s)
    i = int(np.argmax(np.diag(r)))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = np.sqrt(1.0 + r[i, i] - r[j, j] - r[k, k]) * 2
    q = [0.0, 0.0, 0.0]
    q[i] = 0.25 * s
    q[j] = (r[j, i] + r[i, j]) / s
    q[k] = (r[k, i] + r[i, k]) / s
    return (q[0], q[1], q[2], (r[k, j] - r[j, k]) / s)


def inverse(T) -> np.ndarray:
    """Inverse of a rigid 4 x 4 transform (R^T, -R^T t)."""
    out = np.eye(4)
    out[:3, :3] = T[:3, :3].T
    out[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return out


def slerp(q0, q1, f: float) -> np.ndarray:
    """Spherical interpolation of unit quaternions (x, y, z, w), the shorter way round."""
    q0 = np.asarray(q0, dtype=np.float64)
    q1 = np.asarray(q1, dtype=np.float64)
    d = float(np.dot(q0, q1))
    if d < 0.0:
        q1, d = -q1, -d
    if d > 0.9995:  # nearly equal: linear, then normalise (avoids dividing by sin ~ 0)
        q = q0 + f * (q1 - q0)
        return q / np.linalg.norm(q)
    theta = np.arccos(min(d, 1.0))
    return (np.sin((1 - f) * theta) * q0 + np.sin(f * theta) * q1) / np.sin(theta)


class _Edge:
    """parent <- child transforms over time (or one static transform)."""

    def __init__(self, parent: str, static: bool):
        self.parent = parent
        self.static = static
        self.stamps: List[int] = []
        self.translations: List[np.ndarray] = []
        self.rotations: List[np.ndarray] = []

    def add(self, stamp: int, translation, rotation):
        t = np.asarray(translation, dtype=np.float64)
        q = np.asarray(rotation, dtype=np.float64)
        q = q / np.linalg.norm(q)
        if self.static:  # the newest static transform replaces the old one
            self.stamps, self.translations, self.rotations = [stamp], [t], [q]
            return
        i = bisect.bisect_left(self.stamps, stamp)
        if i < len(self.stamps) and self.stamps[i] == stamp:  # same stamp: newest wins
            self.translations[i], self.rotations[i] = t, q
            return
        self.stamps.insert(i, stamp)
        self.translations.insert(i, t)
        self.rotations.insert(i, q)

    def forget_before(self, stamp: int):
        """Drops samples older than `stamp`, keeping the one just before it (to interpolate)."""
        if self.static:
            return
        i = max(bisect.bisect_left(self.stamps, stamp) - 1, 0)
        del self.stamps[:i], self.translations[:i], self.rotations[:i]

    def at(self, stamp: int) -> np.ndarray:
        """T_parent_child at the stamp; raises _OutOfRange when outside the samples."""
        if self.static:
            return matrix(self.translations[0], self.rotations[0])
        i = bisect.bisect_left(self.stamps, stamp)
        if i < len(self.stamps) and self.stamps[i] == stamp:
            return matrix(self.translations[i], self.rotations[i])
        if i == 0 or i == len(self.stamps):
            raise _OutOfRange(self)
        t0, t1 = self.stamps[i - 1], self.stamps[i]
        f = (stamp - t0) / (t1 - t0)
        translation = self.translations[i - 1] + f * (self.translations[i] - self.translations[i - 1])
        return matrix(translation, slerp(self.rotations[i - 1], self.rotations[i], f))


class _OutOfRange(Exception):
    def __init__(self, edge):
        super().__init__()
        self.edge = edge


class TfBuffer:
    """Every transform of a recording, queried at any stamp inside it."""

    def __init__(self):
        self._edges: Dict[str, _Edge] = {}  # child -> edge to its parent

    def add(self, parent: str, child: str, stamp_ns: int, translation, rotation_xyzw,
            static: bool = False):
        parent, child = parent.lstrip("/"), child.lstrip("/")
        edge = self._edges.get(child)
        if edge is None or edge.parent != parent or edge.static != static:
            edge = self._edges[child] = _Edge(parent, static)  # a re-parented frame starts anew
        edge.add(int(stamp_ns), translation, rotation_xyzw)

    def add_message(self, msg, static: bool = False) -> int:
        """Adds a tf2_msgs/TFMessage (rosbags or ROS message object); returns how many."""
        for t in msg.transforms:
            s = t.header.stamp
            stamp = int(s.sec) * 1_000_000_000 + int(getattr(s, "nanosec", getattr(s, "nsec", 0)))
            tr, q = t.transform.translation, t.transform.rotation
            self.add(t.header.frame_id, t.child_frame_id, stamp, (tr.x, tr.y, tr.z),
                     (q.x, q.y, q.z, q.w), static)
        return len(msg.transforms)

    def forget_before(self, stamp_ns: int):
        """Drops /tf samples older than the stamp (a live buffer's cache time, as tf2's)."""
        for edge in self._edges.values():
            edge.forget_before(int(stamp_ns))

    @property
    def frames(self) -> List[str]:
        names = set(self._edges)
        names.update(e.parent for e in self._edges.values())
        return sorted(names)

    def time_range(self) -> Tuple[int, int]:
        """(first, last) stamp of the dynamic transforms, ns; (0, 0) when there are none."""
        stamps = [s for e in self._edges.values() if not e.static for s in e.stamps]
        return (min(stamps), max(stamps)) if stamps else (0, 0)

    def _describe_range(self) -> str:
        first, last = self.time_range()
        if first == last == 0:
            return "the buffer holds static transforms only"
        return f"the buffer holds /tf from {seconds(first)} to {seconds(last)}"

    def _chain(self, frame: str) -> List[str]:
        chain = [frame]
        while chain[-1] in self._edges:
            chain.append(self._edges[chain[-1]].parent)
            if len(chain) > 1000:
                raise TfError(f"TF has a loop through frame '{frame}'")
        return chain

    def lookup(self, target: str, source: str, stamp_ns: int) -> np.ndarray:
        """4 x 4 T_target_source at the stamp (maps points in `source` to `target`)."""
        target, source = target.lstrip("/"), source.lstrip("/")
        if target == source:  # as tf2: a frame is itself at every time, known or not
            return np.eye(4)
        known = self.frames
        for frame in (target, source):
            if frame not in known:
                raise TfError(f"cannot transform '{source}' to '{target}': frame '{frame}' is "
                              f"not in the TF buffer (frames: {', '.join(known) or 'none'})")
        up, down = self._chain(source), self._chain(target)
        common = next((f for f in up if f in down), None)
        if common is None:
            raise TfError(f"cannot transform '{source}' to '{target}': they are in separate TF "
                          f"trees (roots '{up[-1]}' and '{down[-1]}')")
        try:
            T_common_source = np.eye(4)
            for child in up[: up.index(common)]:
                T_common_source = self._edges[child].at(stamp_ns) @ T_common_source
            T_common_target = np.eye(4)
            for child in down[: down.index(common)]:
                T_common_target = self._edges[child].at(stamp_ns) @ T_common_target
        except _OutOfRange as e:
            edge = e.edge
            child = next(c for c, x in self._edges.items() if x is edge)
            first, last = edge.stamps[0], edge.stamps[-1]
            direction = ("before the first" if stamp_ns < first else "after the last")
            gap = (first - stamp_ns) if stamp_ns < first else (stamp_ns - last)
            raise TfError(
                f"cannot transform '{source}' to '{target}' at {seconds(stamp_ns)}: the stamp is "
                f"{gap / 1e9:.3f} s {direction} transform '{edge.parent}' -> '{child}' "
                f"({len(edge.stamps)} transforms from {seconds(first)} to {seconds(last)}; "
                f"{self._describe_range()})") from None
        if np.array_equal(T_common_target, np.eye(4)):
            return T_common_source
        return inverse(T_common_target) @ T_common_source
