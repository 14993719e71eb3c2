"""The last few values of a pure function, kept by key in a bounded store that threads share."""

from __future__ import annotations

import threading


class Recent:
    """The values of the last :attr:`size` keys (the oldest let go first), under a lock."""

    def __init__(self, size: int):
        self.size = size
        self._values: dict = {}
        self._lock = threading.Lock()

    def get(self, key):
        """The value kept for ``key``, or None."""
        with self._lock:
            return self._values.get(key)

    def keep(self, key, value):
        """Keep ``value`` for ``key`` (letting the oldest go when full); returns it."""
        with self._lock:
            if key not in self._values and len(self._values) >= self.size:
                del self._values[next(iter(self._values))]
            self._values[key] = value
        return value
