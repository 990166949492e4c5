"""A live TF buffer: tf_buffer.TfBuffer (chains, interpolation, its reasons) filled from /tf and
/tf_static by one thread while another waits for the transform of a cloud's stamp, with /tf
older than the cache time forgotten. No ROS: the node hands it the TFMessages."""
import threading
import time

from ..tf_buffer import TfBuffer, TfError


class WaitingTf:
    def __init__(self, cache_time_s: float = 10.0):
        self.buffer = TfBuffer()
        self.cache_ns = int(cache_time_s * 1e9)
        self._cv = threading.Condition()
        self._newest = 0

    def add_message(self, msg, static: bool = False):
        with self._cv:
            self.buffer.add_message(msg, static)
            if not static:
                for t in msg.transforms:
                    s = t.header.stamp
                    self._newest = max(self._newest, int(s.sec) * 1_000_000_000 + int(s.nanosec))
                self.buffer.forget_before(self._newest - self.cache_ns)
            self._cv.notify_all()

    def lookup(self, target: str, source: str, stamp_ns: int, timeout_s: float):
        """T_target_source at the stamp, waiting up to timeout_s for it; raises TfError with the
        buffer's reason and how long it waited."""
        deadline = time.monotonic() + timeout_s
        with self._cv:
            while True:
                try:
                    return self.buffer.lookup(target, source, stamp_ns)
                except TfError as e:
                    left = deadline - time.monotonic()
                    # Transforms older than the buffer's first will not come any more.
                    if left <= 0 or "before the first transform" in str(e):
                        raise TfError(f"{e}; waited {timeout_s - max(left, 0):.2f} s") from None
                    self._cv.wait(left)
