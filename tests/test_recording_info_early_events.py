"""`aeroexec info` joins an end event written before its own activation call.

A behavior whose on_start fails (here: a stuck motor refuses every command) ends inside
its activate_behavior call, so the recording holds its event first."""

from __future__ import annotations

from pathlib import Path

from aeroexec.mission import APPENDIX_C, SessionConfig, simulate
from aeroexec.recording import recording_info
from aeroexec.vehicles.world import WORLDS_DIR


def test_failed_start_is_one_run_not_two(tmp_path: Path) -> None:
    out = tmp_path / "faults.mcap"
    simulate(SessionConfig(mission=APPENDIX_C, world=WORLDS_DIR / "faults.yaml", record=out))
    runs = recording_info(out).behaviors
    assert [(r.behavior, r.outcome) for r in runs][-3:] == [
        ("ROTATE", "PROCESS_FAILURE"),
        ("GO_TO_POINT", "PROCESS_FAILURE"),
        ("LAND", "PROCESS_FAILURE"),
    ]
    assert len(runs) == 7
    assert all(r.requested_ns is not None and r.outcome for r in runs)


def test_record_creates_missing_directories(tmp_path: Path) -> None:
    out = tmp_path / "out" / "nested" / "flight.mcap"
    simulate(SessionConfig(mission=APPENDIX_C, record=out))
    assert recording_info(out).complete
