"""Open-loop replay: recorded inputs into an executive with a new catalog.

Only the executive's decisions can differ (the vehicle state and the behaviors' own
outcomes are the recorded ones), so a closed-loop consequence such as "the way home is
now short" must NOT appear here, while rejections, preemptions, process changes and
timeouts must.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from test_replay_support import (
    APPENDIX_C,
    WATCH,
    catalog_for,
    kinds,
    messages,
    record,
    record_live_like,
)

from aeroexec.behaviors import STANDARD_LIBRARY
from aeroexec.executive.clock import SimClock
from aeroexec.recording import open_recording
from aeroexec.replay import Mode, ReplayOptions, ReplayResult, extract_outcome, replay_recording
from aeroexec.replay.outcome import CommandOutcome
from aeroexec.replay.source import SourceMessage
from aeroexec.replay.standins import Script, stand_in_library
from aeroexec.replay.vehicle import ReplayVehicle


@pytest.fixture(scope="module")
def work(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("replay_open")


@pytest.fixture(scope="module")
def recs(work: Path) -> dict[str, Path]:
    return {
        "appendix_c": record(work / "appendix_c.mcap", APPENDIX_C),
        "watch": record(work / "watch.mcap", WATCH),
        "live": record_live_like(work / "live.mcap", start_s=1000.0),
    }


def open_replay(path: Path, catalog: Path | None = None, **options: Any) -> ReplayResult:
    return replay_recording(
        path,
        ReplayOptions(catalog=str(catalog) if catalog else None, mode=Mode.open, **options),
    )


@pytest.mark.parametrize(("name", "commands"), [("appendix_c", 9), ("watch", 10), ("live", 6)])
def test_unchanged_catalog_gives_no_difference(
    recs: dict[str, Path], name: str, commands: int
) -> None:
    result = open_replay(recs[name])
    assert result.mode == "open"
    assert result.diff is not None
    assert result.diff.compared == commands
    assert kinds(result) == []


def test_live_recordings_default_to_open_loop(recs: dict[str, Path]) -> None:
    result = replay_recording(recs["live"], ReplayOptions())
    assert result.mode == "open"
    assert kinds(result) == []
    # Its times start at 1000 s: the replay's end events line up with them.
    assert any("start at 1000.000 s" in note for note in result.notes)


def test_narrowed_range_rejects_without_closed_loop_consequences(
    recs: dict[str, Path], work: Path
) -> None:
    result = open_replay(recs["appendix_c"], catalog_for(work, "narrowed"))
    # No "#6 now ends after 0.1 s": in open loop the way home took what it took.
    assert kinds(result) == [(4, "accepted")]
    assert messages(result) == [
        "#4 GO_TO_POINT coordinates=[3, 5.5, 1.3] now rejected: GO_TO_POINT: COORDINATES needs 3 "
        "numbers in [-2, 2], got [3, 5.5, 1.3] (3 is outside)"
    ]


def test_new_incompatibility(recs: dict[str, Path], work: Path) -> None:
    result = open_replay(recs["appendix_c"], catalog_for(work, "incompatible"))
    assert kinds(result) == [
        (1, "end_event"),
        (2, "preemptions"),
        (2, "capabilities"),
        (2, "processes"),
        (7, "accepted"),
    ]


def test_capability_processes_changed(recs: dict[str, Path], work: Path) -> None:
    result = open_replay(recs["appendix_c"], catalog_for(work, "processes"))
    assert kinds(result) == [(2, "processes"), (4, "processes"), (6, "processes")]


def test_shortened_timeout_without_final_state(recs: dict[str, Path], work: Path) -> None:
    result = open_replay(recs["appendix_c"], catalog_for(work, "timeout"))
    # The final state is the recorded one in open loop: never a difference.
    assert kinds(result) == [(4, "end_event"), (6, "end_event")]
    assert messages(result)[1] == (
        "#6 GO_TO_POINT coordinates=[0, 0, 1.41] now ends TIME_OUT after 3.0 s "
        "(was GOAL_ACHIEVED after 5.3 s): no result within 3 s"
    )


def test_removed_behavior(recs: dict[str, Path], work: Path) -> None:
    result = open_replay(recs["appendix_c"], catalog_for(work, "removed"))
    assert kinds(result) == [(5, "accepted")]


def test_live_recording_with_a_changed_catalog(recs: dict[str, Path], work: Path) -> None:
    result = replay_recording(
        recs["live"], ReplayOptions(catalog=str(catalog_for(work, "incompatible")))
    )
    assert result.mode == "open"
    assert kinds(result) == [
        (1, "end_event"),
        (2, "preemptions"),
        (2, "capabilities"),
        (2, "processes"),
        (4, "accepted"),
    ]


def test_open_replay_recording_matches_its_outcome(recs: dict[str, Path], work: Path) -> None:
    """-o writes the open-loop replay; read back, it summarizes to what the replay
    reported (offset back to the recorded times is the only change)."""
    out = work / "live.open.mcap"
    result = open_replay(recs["live"], catalog_for(work, "removed"), output=str(out))
    assert result.output == str(out)
    replayed = extract_outcome(out)
    original = extract_outcome(recs["live"])
    assert [c.key for c in replayed.commands] == [c.key for c in original.commands]
    assert [c.accepted for c in replayed.commands] == [True, True, True, False, True, True]
    assert open_recording(out).metadata["aeroexec"]["replay_mode"] == "open"


# -- the pieces --------------------------------------------------------------------------------
def _states(*rows: tuple[int, float]) -> list[SourceMessage]:
    return [
        SourceMessage(
            "vehicle/state",
            t,
            (
                f'{{"position":[0,0,{z}],"velocity":[0,0,0],"yaw":0,"battery":0.9,'
                f'"flying":{"true" if z > 0 else "false"}}}'
            ).encode(),
        )
        for t, z in rows
    ]


def test_replay_vehicle_gives_the_latest_recorded_state() -> None:
    clock = SimClock()
    offset = 5_000_000_000
    rows = _states((offset + 100_000_000, 0.5), (offset + 300_000_000, 1.0))
    vehicle = ReplayVehicle(iter(rows), clock, offset)
    assert vehicle.state().position[2] == 0.5  # before the first record: the first state
    clock.advance()  # 0.1 s
    assert vehicle.state().position[2] == 0.5
    clock.advance()  # 0.2 s: still the 0.1 s record
    assert vehicle.state().position[2] == 0.5
    clock.advance()  # 0.3 s
    assert vehicle.state().position[2] == 1.0
    assert vehicle.state().flying
    vehicle.go_to(9, 9, 9)  # commands change nothing: the recording says what happened
    assert vehicle.state().position == (0.0, 0.0, 1.0)


def test_replay_vehicle_skips_undecodable_states() -> None:
    clock = SimClock()
    bad = SourceMessage("vehicle/state", 0, b"not json")
    also_bad = SourceMessage("vehicle/state", 0, b'{"position": "up"}')
    vehicle = ReplayVehicle(iter([bad, also_bad, *_states((0, 2.0))]), clock)
    assert vehicle.state().position[2] == 2.0


def test_stand_ins_end_as_recorded_and_inherit_situation_checks() -> None:
    from aeroexec.catalog.loader import load_catalog
    from aeroexec.catalog.paths import DEFAULT_CATALOG
    from aeroexec.executive.executive import Executive
    from aeroexec.vehicles.null import NullVehicle

    catalog = load_catalog(DEFAULT_CATALOG)
    script = Script()
    library = stand_in_library(catalog, script, STANDARD_LIBRARY)
    executive = Executive(catalog, vehicle=NullVehicle(), library=library)
    land = CommandOutcome(0, 0, "execute_behavior", "LAND")
    script.arm(land)  # no recorded answer: the real LAND's check runs (on the ground)
    refused = executive.activate_behavior("LAND")
    assert not refused.ok
    assert refused.error == "LAND: not flying"

    wait = CommandOutcome(
        1,
        0,
        "execute_behavior",
        "WAIT",
        {"DURATION": 5},
        accepted=True,
        situation=(True, ""),
        end_code="WRONG_PROGRESS",
        end_ns=700_000_000,
        end_detail="x",
    )
    script.arm(wait)
    assert executive.activate_behavior("WAIT", {"DURATION": 5}).ok
    executive.run_for(0.6)
    assert executive.active_behaviors == ("WAIT",)
    executive.run_for(0.1)
    assert executive.events[-1].code.value == "WRONG_PROGRESS"
    assert executive.events[-1].time_ns == 700_000_000


def test_replay_vehicle_is_a_vehicle() -> None:
    from aeroexec.vehicles.base import Vehicle

    assert isinstance(ReplayVehicle(iter(()), SimClock()), Vehicle)
