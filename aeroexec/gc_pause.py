"""Pause Python's cyclic garbage collector while building large object graphs.

Loading a 10,000-behavior catalog creates millions of small objects (YAML nodes, marks,
descriptors, indexes) that live on; each collection of the oldest generation walks all
of them again, so with the collector running, PyYAML's own load spends two thirds of
its time in it, and the cost grows faster than the catalog. The collector is paused
while they are built (nested pauses are fine; an already disabled collector stays so).

When the outermost pause ends, everything allocated meanwhile is still in the youngest
generation, and the first allocation after `gc.enable()` would make the collector walk
all of it (a second per 10 million objects). `gc.freeze()` followed by `gc.unfreeze()`
moves every tracked object to the oldest generation in constant time instead: nothing
is leaked (a later full collection still sees them), nothing is walked now.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def paused_gc() -> Iterator[None]:
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.freeze()
            gc.unfreeze()
            gc.enable()
