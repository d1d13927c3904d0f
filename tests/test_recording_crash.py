"""Crash safety: a recording process killed with SIGKILL loses at most the flush bound
of its clock; `recover` returns everything before it.

- Simulated sessions (count and size only): at most the last 99 messages. Victims,
  each killed at several points: `aeroexec run --output` on a looping mission, and a
  small driver (tests/fixtures/recording/drive_executive.py) that prints exactly how
  many messages it has handed to the recorder.
- Live flights (also 0.5 s of wall-clock time): `aeroexec fly --output` against
  `aeroexec mavsim`, killed while the vehicle hovers, where a flight records ~40
  messages a second, so 99 messages would be 2-3 s of it.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from live_helpers import AeroexecProcess, free_udp_port, write_mission
from mcap.reader import make_reader
from mcap.records import Message as McapMessage
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.recording import FLUSH_INTERVAL_NS, FLUSH_MESSAGES, open_recording, recover
from aeroexec.recording.scan import RecordScanner

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


def _chunks(path: Path) -> list[list[int]]:
    """The log times of the messages of each complete chunk of a (cut) file."""
    chunks: dict[int, list[int]] = {}
    for offset, record in RecordScanner(path).records():
        if isinstance(record, McapMessage):
            chunks.setdefault(offset, []).append(record.log_time)
    return list(chunks.values())


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
    written, flushed, _clock_ns = (int(x) for x in lines[-1].split())
    fixed = tmp_path / "fixed.mcap"
    report = recover(broken, fixed)
    recovered = _messages(fixed)
    assert not report.source_complete
    assert report.messages == len(recovered)
    # The bound: nothing the recorder had flushed is lost, and at most 99 of what it had
    # been handed (the process may have written more before the signal arrived).
    assert len(recovered) >= flushed
    assert len(recovered) >= written - (FLUSH_MESSAGES - 1)
    # A simulated session has no time bound: every chunk holds exactly 100 messages,
    # however much clock time they span (here ~0.6 s: a live bound would cut them).
    chunks = _chunks(broken)
    assert all(len(chunk) == FLUSH_MESSAGES for chunk in chunks)
    if target > 1:
        assert max(chunk[-1] - chunk[0] for chunk in chunks) >= FLUSH_INTERVAL_NS
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


# -- live: the wall-clock bound --------------------------------------------------------------
HOVER_MISSION = """\
    api.executeBehavior("TAKE_OFF")
    print("hovering", flush=True)
    api.executeBehavior("KEEP_HOVERING", duration=120)
    api.executeBehavior("LAND")
"""


@pytest.fixture
def processes() -> Iterator[list[AeroexecProcess]]:
    started: list[AeroexecProcess] = []
    yield started
    for process in started:
        process.kill()


@pytest.mark.parametrize("hover_s", [1.5, 4.0])
def test_killed_fly_loses_at_most_half_a_second_of_wall_clock(
    tmp_path: Path, processes: list[AeroexecProcess], hover_s: float
) -> None:
    port = free_udp_port()
    broken = tmp_path / "flight.mcap"
    mission = write_mission(tmp_path, HOVER_MISSION)
    flight = AeroexecProcess(
        ["fly", str(mission), "--connect", f"udpin:127.0.0.1:{port}", "--output", str(broken)]
    )
    processes.append(flight)
    flight.wait_for("waiting for a heartbeat")
    autopilot = AeroexecProcess(
        [
            *("mavsim", "--connect", f"udpout:127.0.0.1:{port}"),
            *("--speed-factor", "5", "--heartbeat-hz", "4", "--duration", "60"),
        ]
    )
    processes.append(autopilot)
    flight.wait_for("hovering", timeout=30)
    time.sleep(hover_s)
    flight.popen.send_signal(signal.SIGKILL)
    flight.popen.wait(10)
    assert flight.popen.returncode == -signal.SIGKILL
    autopilot.stop()

    fixed = tmp_path / "fixed.mcap"
    report = recover(broken, fixed)
    assert not report.source_complete
    recording = open_recording(fixed)
    took_off = [
        item.log_time_ns
        for item in recording.records()
        if getattr(item, "name", "") == "behavior_event"
        and item.data.get("name") == "TAKE_OFF"
        and item.data.get("code") == "GOAL_ACHIEVED"
    ]
    last = max(m.log_time_ns for m in recording.messages())
    # The mission printed right after TAKE_OFF ended and then hovered `hover_s` until the
    # kill, recording every tick: the file keeps all but the last 0.5 s (and 0.5 s of
    # slack for a busy machine). By count alone, 99 messages here span 2-3 s.
    assert len(took_off) == 1
    assert last >= took_off[0] + round((hover_s - 2 * FLUSH_INTERVAL_NS / 1e9) * 1e9)
    # Every chunk was closed by the bound: before its 100th message, or as soon as its
    # messages spanned 0.5 s of the flight's clock (its last message the one that did).
    chunks = _chunks(broken)
    assert len(chunks) >= 3
    for chunk in chunks:
        assert len(chunk) <= FLUSH_MESSAGES
        assert chunk[-2 if len(chunk) > 1 else -1] - chunk[0] < FLUSH_INTERVAL_NS
    assert any(chunk[-1] - chunk[0] >= FLUSH_INTERVAL_NS for chunk in chunks)
