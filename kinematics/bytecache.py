"""The one in-memory cache: least-recently-used, bounded by the bytes of its values.

Definition: after every ``put``, the least recently used entries are evicted until
``sum(nbytes(v)) <= max_bytes`` (and, when given, ``len <= max_entries``); a single value larger
than the budget is not kept. :func:`nbytes` estimates what an object holds (numpy buffers, bytes,
meshes, and the containers and dataclasses around them).

Every cache of the package is a :class:`ByteLRU`: the explorer's shell, orientation, Optimize-run
and Paper caches, the API's result and shell-file caches, the job history's results (through
:func:`nbytes`) and the memory side of :class:`kinematics.sweep.ResultCache`, so the server's memory
is the sum of stated budgets plus the jobs running at the moment (README, "Security model and
limits").
"""

from __future__ import annotations

import collections
import dataclasses
import sys
import threading
from collections.abc import Callable, Hashable
from typing import Any

import numpy as np

__all__ = ["nbytes", "ByteLRU"]


def nbytes(obj: Any, _seen: set[int] | None = None) -> int:
    """Approximate bytes held by ``obj`` and what it references (each object counted once).

    Counts numpy array buffers (``nbytes``), ``bytes``/``bytearray`` lengths, strings, and
    recurses into dicts, lists, tuples, sets, dataclasses and plain objects' ``__dict__``
    (trimesh meshes are counted by their vertex and face arrays).
    """
    seen = _seen if _seen is not None else set()
    if id(obj) in seen or obj is None:
        return 0
    seen.add(id(obj))
    if isinstance(obj, np.ndarray):
        return int(obj.nbytes) if obj.base is None or id(obj.base) not in seen else 0
    if isinstance(obj, (bytes, bytearray, memoryview)):
        return len(obj)
    if isinstance(obj, (str, int, float, bool, complex)):
        return sys.getsizeof(obj)
    if isinstance(obj, dict):
        return 64 + sum(nbytes(k, seen) + nbytes(v, seen) for k, v in obj.items())
    if isinstance(obj, (list, tuple, set, frozenset)):
        return 56 + sum(nbytes(v, seen) for v in obj)
    verts = getattr(obj, "vertices", None)
    faces = getattr(obj, "faces", None)
    if isinstance(verts, np.ndarray) and isinstance(faces, np.ndarray):  # a mesh: its arrays (+ caches)
        return 2 * (int(verts.nbytes) + int(faces.nbytes))
    if dataclasses.is_dataclass(obj):
        return 64 + sum(nbytes(getattr(obj, f.name, None), seen) for f in dataclasses.fields(obj))
    d = getattr(obj, "__dict__", None)
    if isinstance(d, dict):
        return 64 + sum(nbytes(v, seen) for v in d.values())
    return sys.getsizeof(obj)


class ByteLRU:
    """A thread-safe least-recently-used map bounded by the estimated bytes of its values.

    Args:
        max_bytes: budget; after each ``put`` the oldest entries are evicted until the total is
            at most this. A value larger than the budget is not stored (``put`` returns False).
        on_evict: called with each evicted value (outside the lock).
        size: how to measure a value (default :func:`nbytes`).
        max_entries: also keep at most this many entries (``None``: no count limit).
    """

    def __init__(self, max_bytes: int, on_evict: Callable[[Any], None] | None = None,
                 size: Callable[[Any], int] = nbytes, *, max_entries: int | None = None) -> None:
        if max_bytes < 0:
            raise ValueError(f"max_bytes = {max_bytes!r} is invalid: valid range >= 0")
        if max_entries is not None and max_entries < 0:
            raise ValueError(f"max_entries = {max_entries!r} is invalid: valid range >= 0 (or None)")
        self.max_bytes = int(max_bytes)
        self.max_entries = max_entries
        self._on_evict = on_evict
        self._size = size
        self._lock = threading.Lock()
        self._data: collections.OrderedDict[Hashable, tuple[Any, int]] = collections.OrderedDict()
        self._total = 0

    def get(self, key: Hashable) -> Any:
        """The value (and mark it recently used), or ``None``."""
        with self._lock:
            hit = self._data.get(key)
            if hit is None:
                return None
            self._data.move_to_end(key)
            return hit[0]

    def put(self, key: Hashable, value: Any) -> bool:
        """Store ``value``; returns False when it alone exceeds the budget (then nothing is kept)."""
        n = int(self._size(value))
        evicted: list[Any] = []
        with self._lock:
            old = self._data.pop(key, None)
            if old is not None:
                self._total -= old[1]
                if old[0] is not value:
                    evicted.append(old[0])
            stored = n <= self.max_bytes and self.max_entries != 0
            if stored:
                self._data[key] = (value, n)
                self._total += n
            while self._data and (self._total > self.max_bytes
                                  or (self.max_entries is not None and len(self._data) > self.max_entries)):
                _, (v, m) = self._data.popitem(last=False)
                self._total -= m
                evicted.append(v)
        if self._on_evict is not None:
            for v in evicted:
                try:
                    self._on_evict(v)
                except Exception:  # noqa: BLE001 - eviction hooks must not break a put
                    pass
        return stored

    @property
    def total_bytes(self) -> int:
        """Estimated bytes held now."""
        with self._lock:
            return self._total

    def __len__(self) -> int:
        with self._lock:
            return len(self._data)

    def __contains__(self, key: Hashable) -> bool:
        with self._lock:
            return key in self._data

    def clear(self) -> None:
        """Drop every entry (``on_evict`` is not called)."""
        with self._lock:
            self._data.clear()
            self._total = 0
