"""Replay a ROS 1 or ROS 2 bag: import it into a temporary recording, replay that (open loop by
default: a bag is a real flight), report under the bag's name.

The replay engine reads aeroexec recordings only; `bag_recording` is the bridge any
caller can use (`with bag_recording("flight.bag") as imported: ...`), and `replay_bag`
is what `aeroexec.replay.engine.replay_recording` calls for a bag.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from aeroexec.bags.importer import ImportReport, import_bag
from aeroexec.bags.mapping import Mapping
from aeroexec.errors import AeroexecError, Mark, RecordingError

if TYPE_CHECKING:
    from aeroexec.replay.engine import ReplayOptions, ReplayResult


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


def _renamed(exc: AeroexecError, temp: Path, bag: str) -> AeroexecError:
    """The same error, naming the bag instead of the temporary recording."""
    if exc.mark is None or exc.mark.file != str(temp):
        return exc
    mark = replace(exc.mark, file=bag)
    return type(exc)(exc.message, mark)


def replay_bag(path: str | os.PathLike[str], options: ReplayOptions) -> ReplayResult:
    """`replay_recording` for a bag (imported with the shipped mapping: Aerostack's for a
    ROS 1 bag, Aerostack2's for a ROS 2 one). An Aerostack2 flight has no catalog of its
    own: the replay runs its behavior timeline (the reconstructed activations, with the
    goals as arguments, each ending as recorded) against the `--catalog` given."""
    from aeroexec.replay.engine import replay_recording

    with bag_recording(path) as imported:
        if not imported.report.derived.get("mission/command"):
            known = (
                "the Aerostack mapping knows (behavior_event, list_of_active_behaviors, "
                "command topics)"
                if imported.report.ros_version == 1
                else "the Aerostack2 mapping knows (<ns>/<Behavior>/_behavior/behavior_status: "
                "rosbag2 records it only with --include-hidden-topics)"
            )
            raise RecordingError(
                f"no behavior commands to replay: the bag has none of the behavior topics "
                f"{known}; `aeroexec import --mapping` then replay the .mcap",
                Mark(str(path)),
            )
        try:
            result = replay_recording(imported.path, options)
        except AeroexecError as exc:
            raise _renamed(exc, imported.path, str(path)) from None
    notes = [f"imported from the bag: {note}" for note in imported.report.notes]
    reconstructed = (
        imported.report.reconstructed_activations + imported.report.reconstructed_inhibitions
    )
    if reconstructed:
        source = (
            "active-behavior list (bags hold no service calls)"
            if imported.report.ros_version == 1
            else "behavior status (Aerostack2 starts behaviors with action goals)"
        )
        notes.append(
            f"{reconstructed} of the recorded commands were reconstructed from the bag's {source}"
        )
    return replace(result, recording=str(path), notes=(*result.notes, *notes))
