"""Pause Python's cyclic garbage collector while building large object graphs.

Loading a 10,000-behavior catalog creates millions of small objects (YAML nodes, marks,
descriptors) that live on; each collection of the oldest generation walks all of them
again, so with the collector running, PyYAML's own load spends two thirds of its time in
it, and the cost grows faster than the catalog. None of these objects form reference
cycles that need collecting, so the collector is paused while they are built and
restored afterwards (nested pauses are fine; an already disabled collector stays so).
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
            gc.enable()
