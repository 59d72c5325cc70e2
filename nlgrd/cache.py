"""A bounded store of derived data, kept on the object it belongs to (a gear geometry,
a mesh, a state space): nothing of nlgrd caches in module globals."""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable
from typing import Any


class BoundedCache:
    """At most ``maxsize`` entries, the oldest dropped first (first in, first out).

    Keys are tuples of hashables; :meth:`get` computes a missing entry with ``make``.
    A pickled cache keeps only its ``maxsize``: it is unpickled empty.

    Parameters
    ----------
    maxsize : int
        The largest number of entries kept.

    Attributes
    ----------
    maxsize : int
        The largest number of entries kept.
    """

    def __init__(self, maxsize: int = 16):
        self.maxsize = int(maxsize)
        self._data: OrderedDict = OrderedDict()

    def get(self, key, make: Callable[[], Any]):
        """The entry for ``key``, computed by ``make()`` when missing."""
        if key in self._data:
            return self._data[key]
        value = make()
        self.put(key, value)
        return value

    def peek(self, key):
        """The entry for ``key``, or None."""
        return self._data.get(key)

    def put(self, key, value) -> None:
        """Store ``value`` under ``key`` (the oldest entry goes when full)."""
        if key not in self._data and len(self._data) >= self.maxsize:
            self._data.popitem(last=False)
        self._data[key] = value

    def __len__(self) -> int:
        return len(self._data)

    def __getstate__(self):  # a pickled object does not carry its cache
        return {"maxsize": self.maxsize}

    def __setstate__(self, state):
        self.maxsize = state["maxsize"]
        self._data = OrderedDict()
