"""Closed-loop replay runs no code from the recording unless the user says so.

The mission script a session recorded (`mission.py`) is code; a recording is data a user
may receive from anyone. Replaying one must not run its script unless
`--trust-recording` is given; `--mission FILE` runs the user's own copy instead.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.mission.session import SessionConfig, simulate
from aeroexec.recording import open_recording

runner = CliRunner()

#: A mission with a side effect: it leaves a file behind whenever it runs.
TROJAN = """\
import pathlib
import executive_engine_api as api

pathlib.Path({marker!r}).write_text("ran")

def runMission():
    api.executeBehavior("TAKE_OFF")
    api.executeBehavior("LAND")
"""
CLEAN = """\
import executive_engine_api as api

def runMission():
    api.executeBehavior("TAKE_OFF")
    api.executeBehavior("LAND")
"""


@pytest.fixture()
def recorded(tmp_path: Path) -> tuple[Path, Path]:
    """(a recording whose mission.py writes `marker` when run, `marker`)."""
    marker = tmp_path / "ran.txt"
    script = tmp_path / "received.py"
    script.write_text(TROJAN.format(marker=str(marker)), encoding="utf-8")
    recording = tmp_path / "received.mcap"
    simulate(SessionConfig(mission=script, record=recording))
    assert marker.exists()  # recording it ran it (that was its author's machine)
    marker.unlink()
    script.unlink()
    return recording, marker


def replay(*args: str) -> tuple[int, str]:
    result = runner.invoke(app, ["replay", *args])
    assert result.exception is None or isinstance(result.exception, SystemExit)
    return result.exit_code, result.output


def test_by_default_the_recorded_script_is_not_run(recorded: tuple[Path, Path]) -> None:
    recording, marker = recorded
    code, out = replay(str(recording), "--check")
    assert not marker.exists(), "replay ran the code stored in the recording"
    assert code == 0, out  # the recorded commands replay to the same outcome
    assert "no differences (2 commands compared)" in out
    assert "the recording's mission.py was not run (--trust-recording runs it" in out


def test_the_output_of_an_untrusted_replay_holds_no_script(
    recorded: tuple[Path, Path], tmp_path: Path
) -> None:
    recording, marker = recorded
    out = tmp_path / "replayed.mcap"
    code, _ = replay(str(recording), "-o", str(out))
    assert code == 0 and not marker.exists()
    replayed = open_recording(out)
    assert replayed.attachment("mission.py") is None
    assert replayed.metadata["aeroexec"]["mission"] == "(mission/command stream)"


def test_trust_recording_runs_it(recorded: tuple[Path, Path]) -> None:
    recording, marker = recorded
    code, out = replay(str(recording), "--trust-recording", "--check")
    assert code == 0, out
    assert marker.read_text() == "ran"
    assert "not run" not in out


def test_mission_runs_the_users_copy_and_says_it_differs(
    recorded: tuple[Path, Path], tmp_path: Path
) -> None:
    recording, marker = recorded
    mine = tmp_path / "mine.py"
    mine.write_text(CLEAN, encoding="utf-8")
    code, out = replay(str(recording), "--mission", str(mine), "--check")
    assert code == 0, out
    assert not marker.exists()
    assert f"ran {mine}, which differs from the recording's mission.py" in out


def test_mission_identical_to_the_recorded_one_replays_byte_for_byte(tmp_path: Path) -> None:
    script = tmp_path / "clean.py"
    script.write_text(CLEAN, encoding="utf-8")
    recording = tmp_path / "clean.mcap"
    simulate(SessionConfig(mission=script, record=recording))
    out = tmp_path / "again.mcap"
    code, text = replay(str(recording), "--mission", str(script), "-o", str(out))
    assert code == 0
    assert "differs" not in text
    assert out.read_bytes() == recording.read_bytes()


def test_a_bad_mission_is_one_error(recorded: tuple[Path, Path], tmp_path: Path) -> None:
    recording, _ = recorded
    bad = tmp_path / "bad.py"
    bad.write_text("def runMission(:\n", encoding="utf-8")
    code, out = replay(str(recording), str(recording), "--mission", str(bad))
    assert code == 2
    assert out.strip().splitlines() == [f"{bad}:1:16: error: invalid Python: invalid syntax"]
