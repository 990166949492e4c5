"""A bounded queue that keeps the newest items: a mapper that falls behind maps the latest
clouds and counts the ones it skipped, instead of lagging ever further behind the robot."""
import collections
import threading
from typing import Any, Optional


class LatestQueue:
    def __init__(self, size: int = 1):
        if size < 1:
            raise ValueError(f"queue size must be >= 1, got {size}")
        self._items = collections.deque()
        self._size = size
        self._cv = threading.Condition()
        self._closed = False

    def put(self, item) -> Optional[Any]:
        """Adds an item; returns the oldest one it pushed out when the queue was full."""
        with self._cv:
            dropped = self._items.popleft() if len(self._items) >= self._size else None
            self._items.append(item)
            self._cv.notify()
            return dropped

    def get(self, timeout: Optional[float] = None) -> Optional[Any]:
        """The oldest item, waiting up to `timeout` s; None on timeout or when closed."""
        with self._cv:
            self._cv.wait_for(lambda: self._items or self._closed, timeout)
            return self._items.popleft() if self._items and not self._closed else None

    def resize(self, size: int):
        with self._cv:
            self._size = max(int(size), 1)

    def __len__(self):
        with self._cv:
            return len(self._items)

    def close(self):
        with self._cv:
            self._closed = True
            self._cv.notify_all()
