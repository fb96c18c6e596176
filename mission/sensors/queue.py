"""A bounded frame queue between a driver's thread and the control loop: when the stream is faster than its
consumer the OLDEST frames go (and are counted), so memory never grows and the agents see the freshest data."""

from __future__ import annotations

import threading
from collections import deque
from typing import Generic, TypeVar

T = TypeVar("T")


class DropOldestQueue(Generic[T]):
    """Thread-safe FIFO of at most `capacity` items; `put` on a full queue drops the oldest.

    >>> q: DropOldestQueue[int] = DropOldestQueue(2)
    >>> for i in range(5): q.put(i)
    >>> q.drain(), q.dropped, q.received
    ([3, 4], 3, 5)
    """

    def __init__(self, capacity: int):
        if capacity < 1:
            raise ValueError("capacity must be at least 1")
        self.capacity = capacity
        self._items: deque[T] = deque(maxlen=capacity)
        self._lock = threading.Lock()
        self.dropped = 0
        self.received = 0

    def put(self, item: T) -> None:
        with self._lock:
            if len(self._items) == self._items.maxlen:
                self.dropped += 1
            self._items.append(item)
            self.received += 1

    def drain(self) -> list[T]:
        """Everything queued, oldest first; the queue is empty afterwards."""
        with self._lock:
            items = list(self._items)
            self._items.clear()
        return items

    def __len__(self) -> int:
        with self._lock:
            return len(self._items)
