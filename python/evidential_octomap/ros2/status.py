"""What the node has done and why it dropped what it dropped, as one JSON document (the status
topic): counts by reason, the last drop with its reason, the time of each stage a cloud passes
(reading it, waiting for its transform, waiting for the map lock, the insert) and the map's
size."""
import json
import statistics
import threading
import time
from collections import Counter, deque

# Why a cloud is not in the map, as counted (the reason text of each drop says more).
MALFORMED, NO_SEMANTICS, NO_TRANSFORM, QUEUE_FULL, REFUSED = (
    "malformed", "no_semantic_field", "no_transform", "queue_full", "evidence_refused")
# A cloud's stages, in order: read (its fields and evidence) and tf_wait, on the executor;
# lock_wait (behind the views or a service) and insert, on the insert thread.
STAGES = ("read", "tf_wait", "lock_wait", "insert")


class Status:
    def __init__(self):
        self._lock = threading.Lock()
        self.started = time.monotonic()
        self.received = 0
        self.lost = 0
        self.views_published = 0
        self.views_lock_ms = None
        self.inserted = 0
        self.points = 0
        self.dropped = Counter()
        self.last_drop = None
        self.stage_ms = {stage: deque(maxlen=100) for stage in STAGES}
        self.map = {}
        self.events = deque(maxlen=10)  # parameter changes, saves, resets, with their results

    def lost_in_dds(self, total: int):
        """Clouds the middleware lost before the node saw them (not received, not dropped)."""
        with self._lock:
            self.lost = total

    def received_cloud(self):
        with self._lock:
            self.received += 1

    def drop(self, kind: str, reason: str, stamp_ns: int = 0, frame: str = ""):
        with self._lock:
            self.dropped[kind] += 1
            self.last_drop = {"kind": kind, "reason": reason, "stamp_ns": stamp_ns,
                              "frame": frame}

    def received_stages(self, read_s: float, tf_wait_s: float):
        with self._lock:
            self.stage_ms["read"].append(1000.0 * read_s)
            self.stage_ms["tf_wait"].append(1000.0 * tf_wait_s)

    def inserted_cloud(self, points: int, lock_wait_s: float, insert_s: float):
        with self._lock:
            self.inserted += 1
            self.points += points
            self.stage_ms["lock_wait"].append(1000.0 * lock_wait_s)
            self.stage_ms["insert"].append(1000.0 * insert_s)

    def views(self, lock_seconds: float):
        with self._lock:
            self.views_published += 1
            self.views_lock_ms = 1000.0 * lock_seconds

    def event(self, text: str):
        with self._lock:
            self.events.append(text)

    def set_map(self, tree):
        info = {"leaves": tree.num_leaves, "semantic_nodes": tree.num_semantic_nodes,
                "memory_bytes": tree.memory_usage, "rule": tree.rule,
                "resolution": tree.resolution}
        with self._lock:
            self.map = info

    def as_dict(self, queue_length: int = 0) -> dict:
        with self._lock:
            stages = {f"{stage}_ms_median": round(statistics.median(t), 1) if t else None
                      for stage, t in self.stage_ms.items()}
            insert = self.stage_ms["insert"]
            return {
                "uptime_s": round(time.monotonic() - self.started, 3),
                "clouds_received": self.received,
                "clouds_lost_in_dds": self.lost,
                "clouds_inserted": self.inserted,
                "points_inserted": self.points,
                "clouds_dropped": sum(self.dropped.values()),
                "dropped_by_reason": dict(self.dropped),
                "last_drop": self.last_drop,
                "insert_queue": queue_length,
                **stages,
                "insert_ms_last": round(insert[-1], 1) if insert else None,
                "map": self.map,
                "views_published": self.views_published,
                "views_lock_ms": (round(self.views_lock_ms, 1) if self.views_lock_ms is not None
                                  else None),
                "events": list(self.events),
            }

    def to_json(self, queue_length: int = 0) -> str:
        return json.dumps(self.as_dict(queue_length))
