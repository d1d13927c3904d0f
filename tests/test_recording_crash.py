"""Crash safety: a recording process killed with SIGKILL loses at most the flush bound
(100 messages / 0.5 s of clock time); `recover` returns everything before it.

Two kinds of victims, each killed at several points: `aeroexec run --output` on a
looping mission, and a small driver (tests/fixtures/recording/drive_executive.py) that
prints exactly how many messages it has handed to the recorder.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from mcap.reader import make_reader
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.recording import FLUSH_INTERVAL_NS, FLUSH_MESSAGES, open_recording, recover

DRIVER = Path(__file__).resolve().parent / "fixtures" / "recording" / "drive_executive.py"
LOOP_MISSION = """\
import executive_engine_api as api


def runMission():
    for i in range({limit}):
        api.executeBehavior('TAKE_OFF')
        api.executeBehavior('LAND')
        print("done %d" % i, flush=True)
"""

Message = tuple[str, int, bytes]


def _messages(path: Path) -> list[Message]:
    with open(path, "rb") as stream:
        return [
            (channel.topic, message.log_time, message.data)
            for _, channel, message in make_reader(stream).iter_messages(log_time_order=False)
        ]


def _kill_after(command: list[str], cwd: Path, stop: Callable[[str], bool]) -> list[str]:
    """Run `command`, read stdout lines until `stop(line)` is true, then SIGKILL it.
    Returns the lines read."""
    process = subprocess.Popen(
        command, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True
    )
    lines: list[str] = []
    try:
        assert process.stdout is not None
        for line in process.stdout:
            lines.append(line.strip())
            if stop(lines[-1]):
                break
        process.send_signal(signal.SIGKILL)
    finally:
        process.kill()
        process.wait(timeout=30)
    assert process.returncode == -signal.SIGKILL, "the process ended before it was killed"
    return lines


@pytest.mark.parametrize("target", [1, 3_000, 15_000])
def test_killed_driver_loses_at_most_the_flush_bound(tmp_path: Path, target: int) -> None:
    broken = tmp_path / "killed.mcap"
    lines = _kill_after(
        [sys.executable, str(DRIVER), str(broken)],
        tmp_path,
        lambda line: int(line.split()[0]) >= target,
    )
    written, flushed, clock_ns = (int(x) for x in lines[-1].split())
    fixed = tmp_path / "fixed.mcap"
    report = recover(broken, fixed)
    recovered = _messages(fixed)
    assert not report.source_complete
    assert report.messages == len(recovered)
    # The bound: nothing the recorder had flushed is lost, and at most 99 of what it had
    # been handed (the process may have written more before the signal arrived).
    assert len(recovered) >= flushed
    assert len(recovered) >= written - (FLUSH_MESSAGES - 1)
    # Recovered messages are exactly the start of an uninterrupted run's stream (the run
    # may have gone on after its last line was read: each iteration writes > 30 messages).
    reference = tmp_path / "reference.mcap"
    iterations = max(len(lines), len(recovered) // 30) + 2
    subprocess.run(
        [sys.executable, str(DRIVER), str(reference), str(iterations)],
        cwd=tmp_path,
        check=True,
        capture_output=True,
    )
    expected = _messages(reference)
    assert len(expected) > len(recovered)
    assert recovered == expected[: len(recovered)]
    # ... and every message older than 0.5 s of clock time at the kill is among them.
    old = [i for i, m in enumerate(expected[:written]) if m[1] <= clock_ns - FLUSH_INTERVAL_NS]
    assert not old or old[-1] < len(recovered)
    # The reader sees the same messages in the broken file and says it is incomplete.
    recording = open_recording(broken)
    assert sum(1 for _ in recording.messages()) == len(recovered)
    assert not recording.complete
    assert recording.metadata["aeroexec"]["driver"] == "drive_executive"


def _mission_commands_before(messages: list[Message], iterations_done: int) -> int:
    """Index of the first message of iteration `iterations_done` (each iteration of the
    loop mission starts with its first mission/command): all messages before it had been
    handed to the recorder when the mission printed `done <iterations_done - 1>`."""
    commands = [i for i, m in enumerate(messages) if m[0] == "/drone1/mission/command"]
    return commands[2 * iterations_done]


@pytest.mark.parametrize("kill_after", [0, 4, 12])
def test_killed_aeroexec_run_record_is_recoverable(tmp_path: Path, kill_after: int) -> None:
    mission = tmp_path / "loop.py"
    mission.write_text(LOOP_MISSION.format(limit=10**6))
    broken = tmp_path / "flight.mcap"
    lines = _kill_after(
        # Not -q: the mission's own "done N" lines say how far it got.
        [sys.executable, "-m", "aeroexec", "run", str(mission), "--output", str(broken)],
        tmp_path,
        lambda line: line == f"done {kill_after}",
    )
    assert lines[-1] == f"done {kill_after}"

    result = CliRunner().invoke(app, ["info", str(broken), "--format", "json"])
    assert result.exit_code == 0 and "warning: incomplete recording" in result.stderr
    assert json.loads(result.stdout)["complete"] is False

    fixed = tmp_path / "fixed.mcap"
    result = CliRunner().invoke(app, ["recover", str(broken), "-o", str(fixed)])
    assert result.exit_code == 0, result.output
    recovered = _messages(fixed)

    # The same mission, stopped normally a little later: the reference stream (the killed
    # run may have gone on after its last line was read: an iteration is > 150 messages).
    limit = max(kill_after + 3, len(recovered) // 150 + 2)
    reference_mission = tmp_path / "reference" / "loop.py"
    reference_mission.parent.mkdir()
    reference_mission.write_text(LOOP_MISSION.format(limit=limit))
    reference = tmp_path / "reference.mcap"
    subprocess.run(
        [
            sys.executable,
            "-m",
            "aeroexec",
            "run",
            str(reference_mission),
            "-q",
            "--output",
            str(reference),
        ],
        cwd=tmp_path,
        check=True,
        capture_output=True,
    )
    expected = _messages(reference)
    assert len(expected) > len(recovered)
    assert recovered == expected[: len(recovered)]
    handed = _mission_commands_before(expected, kill_after + 1)
    assert len(recovered) >= handed - (FLUSH_MESSAGES - 1)
    with open(fixed, "rb") as stream:
        attachments = {a.name: a.data for a in make_reader(stream).iter_attachments()}
    assert attachments["mission.py"] == mission.read_bytes()
