"""Helpers shared by the replay and diff tests: recording missions, editing catalogs.

Imported by tests/test_replay_*.py and tests/test_diff*.py (tests/ is on sys.path);
it holds no tests itself beyond checking that its catalog edits still apply.
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Iterable
from pathlib import Path

from aeroexec.behaviors import STANDARD_LIBRARY
from aeroexec.executive.clock import NS_PER_S, SimClock
from aeroexec.executive.executive import Executive
from aeroexec.mission.api import MissionAPI
from aeroexec.mission.session import SessionConfig, simulate
from aeroexec.recording import Recorder
from aeroexec.replay import ReplayResult
from aeroexec.vehicles.sim import SimVehicle

REPO = Path(__file__).resolve().parent.parent
FIXTURES = REPO / "tests" / "fixtures" / "replay"
MISSIONS = FIXTURES / "missions"
APPENDIX_C = REPO / "missions" / "appendix_c.py"
SURVEY = MISSIONS / "survey.py"
WATCH = MISSIONS / "watch.py"
DEFAULT_CATALOG_FILE = REPO / "catalog" / "default.yaml"
V010 = REPO / "recordings" / "appendix_c-v0.1.0.mcap"
RANDOM_MOTOR_WORLD = FIXTURES / "worlds" / "random_motor.yaml"

#: The catalog changes the tests replay against: small edits of catalog/default.yaml.
EDITS: dict[str, list[tuple[str, str]]] = {
    # GO_TO_POINT's COORDINATES narrowed from [-100, 100] to [-2, 2]: rejections.
    "narrowed": [
        (
            "      - argument: COORDINATES\n        allowed_values: [-100, 100]",
            "      - argument: COORDINATES\n        allowed_values: [-2, 2]",
        )
    ],
    # GO_TO_POINT now also preempts PAY_ATTENTION_TO_VISUAL_MARKERS: a new incompatibility.
    "incompatible": [
        (
            "    timeout: 120\n    recurrent: no\n"
            "    incompatible_lists: [motion_behaviors, rotation_behaviors]",
            "    timeout: 120\n    recurrent: no\n"
            "    incompatible_lists: [motion_behaviors, rotation_behaviors, perception]",
        ),
        (
            "  - list: rotation_behaviors\n    behaviors: [ROTATE]\n",
            "  - list: rotation_behaviors\n    behaviors: [ROTATE]\n\n"
            "  - list: perception\n    behaviors: [PAY_ATTENTION_TO_VISUAL_MARKERS]\n",
        ),
    ],
    # PATH_PLANNING loses droneYawPlanner: process transitions change.
    "processes": [
        (
            "    processes: [droneTrajectoryPlanner, droneYawPlanner]",
            "    processes: [droneTrajectoryPlanner]",
        )
    ],
    # GO_TO_POINT's timeout shortened from 120 s to 3 s: TIME_OUT.
    "timeout": [
        ("  - behavior: GO_TO_POINT\n    timeout: 120", "  - behavior: GO_TO_POINT\n    timeout: 3")
    ],
    # ROTATE removed (and from its list): unknown behavior.
    "removed": [
        (
            "  - behavior: ROTATE\n    timeout: 15\n    recurrent: no\n"
            "    incompatible_lists: [motion_behaviors, rotation_behaviors]\n"
            "    capabilities: [SETPOINT_BASED_FLIGHT_CONTROL]\n    arguments:\n"
            "      - argument: ANGLE\n        allowed_values: [-360, 360]\n\n",
            "",
        ),
        ("    behaviors: [ROTATE]", "    behaviors: []"),
    ],
}


def edited_catalog(directory: Path, name: str, edits: Iterable[tuple[str, str]] = ()) -> Path:
    """catalog/default.yaml with `edits` applied (each must match exactly once)."""
    text = DEFAULT_CATALOG_FILE.read_text(encoding="utf-8")
    for old, new in edits:
        assert text.count(old) == 1, f"catalog edit does not apply: {old!r}"
        text = text.replace(old, new)
    path = directory / f"{name}.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def catalog_for(directory: Path, change: str) -> Path:
    return edited_catalog(directory, change, EDITS[change])


def record(
    path: Path,
    mission: Path,
    catalog: Path = DEFAULT_CATALOG_FILE,
    *,
    seed: int = 0,
    world: Path | None = None,
) -> Path:
    """`aeroexec run MISSION --catalog CATALOG --seed S --world W --output PATH`, quietly."""
    config = SessionConfig(mission=mission, catalog=catalog, seed=seed, world=world, record=path)
    with contextlib.redirect_stdout(io.StringIO()):
        simulate(config)
    return path


class OffsetClock(SimClock):
    """A simulated clock that starts at `start_ns` (a log whose times do not start at 0)."""

    def __init__(self, start_ns: int) -> None:
        super().__init__()
        self._start = start_ns
        self.kind = "wall"

    def now_ns(self) -> int:
        return super().now_ns() + self._start


def record_live_like(
    path: Path,
    catalog_path: Path = DEFAULT_CATALOG_FILE,
    *,
    start_s: float = 0.0,
    attach_catalog: bool = True,
) -> Path:
    """A recording like a live flight's: clock "wall" in the metadata, no mission script
    attached (the commands come from an operator), times starting at `start_s`."""
    from aeroexec.catalog.loader import load_catalog

    catalog = load_catalog(catalog_path)
    attachments = {"catalog.yaml": catalog.text} if attach_catalog else {}
    with Recorder(
        path,
        metadata={"clock": "wall", "vehicle": "sim", "seed": "0"},
        attachments=attachments,
    ) as recorder:
        clock = OffsetClock(round(start_s * NS_PER_S))
        executive = Executive(
            catalog,
            vehicle=SimVehicle(),
            clock=clock,
            library=STANDARD_LIBRARY,
            observers=[recorder],
        )
        api = MissionAPI(executive)
        api.execute_behavior("TAKE_OFF")
        api.activate_behavior("PAY_ATTENTION_TO_VISUAL_MARKERS")
        api.execute_behavior("GO_TO_POINT", coordinates=[1, 1, 1.5])
        executive.run_for(1.0)  # the operator waits a second
        api.execute_behavior("ROTATE", angle=90)
        api.inhibit_behavior("PAY_ATTENTION_TO_VISUAL_MARKERS")
        api.execute_behavior("LAND")
    return path


def kinds(result: ReplayResult) -> list[tuple[int | None, str]]:
    """(command index, kind) of every difference, in report order."""
    assert result.error is None, result.error
    assert result.diff is not None
    return [(d.command, d.kind) for d in result.diff.differences]


def messages(result: ReplayResult) -> list[str]:
    assert result.diff is not None
    return [d.message for d in result.diff.differences]


def test_every_catalog_edit_still_applies(tmp_path: Path) -> None:
    """If catalog/default.yaml changes shape, the edits above must be updated: say so
    here rather than as a confusing failure in a replay test."""
    from aeroexec.catalog.loader import load_catalog

    for change in EDITS:
        catalog = load_catalog(catalog_for(tmp_path, change))
        assert catalog.behaviors, change
