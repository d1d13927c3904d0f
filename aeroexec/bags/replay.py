"""A ROS 1 or ROS 2 bag as a temporary aeroexec recording, for the tools that read recordings only.

`bag_recording` is the bridge any caller can use (`with bag_recording("flight.bag") as
imported: ...`): `aeroexec.replay.engine.replay_bag` replays a bag through it (open loop
by default: a bag is a real flight) and reports under the bag's name, and `view` shows
one through it.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from aeroexec.bags.importer import ImportReport, import_bag
from aeroexec.bags.mapping import Mapping


@dataclass(frozen=True, slots=True)
class ImportedBag:
    """A bag imported for the time of a `with` block: `path` is the temporary MCAP."""

    bag: str
    path: Path
    report: ImportReport


@contextmanager
def bag_recording(
    bag: str | os.PathLike[str],
    mapping: Mapping | str | os.PathLike[str] | None = None,
    drone: str | None = None,
) -> Iterator[ImportedBag]:
    """Import `bag` into a temporary aeroexec recording, removed after the block. The
    file is named after the bag (`flight.bag` -> `flight.mcap`), so what reports show of
    it reads naturally."""
    with tempfile.TemporaryDirectory(prefix="aeroexec-bag-") as folder:
        target = Path(folder) / (Path(bag).stem + ".mcap")
        report = import_bag(bag, target, mapping=mapping, drone=drone)
        yield ImportedBag(str(bag), target, report)
