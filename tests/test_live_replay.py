"""`replay --live` (issue 28): one replay served as it runs through the same tap and live
view as `run --live`. A Foxglove WebSocket client (foxglove.sdk.v1) receives exactly the
replay's own recording; --speed paces every kind of replay; a viewer's abort stops the
replay and is recorded as an abort; what a live view cannot show is refused in one line."""

from __future__ import annotations

import json
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from foxglove_client import FoxgloveClient
from live_helpers import AeroexecProcess, write_mission
from test_live import PATROL, Live, assert_parity, live_args

from aeroexec.executive.clock import Paced
from aeroexec.mission.paths import APPENDIX_C
from aeroexec.recording import open_recording
from aeroexec.recording.reader import RecordedTopic
from aeroexec.replay.liveloop import RecordedClock


def aeroexec(*args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "aeroexec", *args], capture_output=True, text=True, timeout=timeout
    )


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Appendix C, run once: the recording the replays replay (18.6 simulated s)."""
    record = tmp_path_factory.mktemp("recorded") / "flight.mcap"
    assert aeroexec("run", str(APPENDIX_C), "-o", str(record), "-q").returncode == 0
    return record


def wait_for_topic(client: FoxgloveClient, topic: str, timeout: float = 60.0) -> None:
    """Until the client has received a message on `topic` (the session is under way)."""
    deadline = time.monotonic() + timeout
    while not any(m.topic == topic for m in list(client.messages)):
        assert time.monotonic() < deadline, f"nothing on {topic}"
        time.sleep(0.05)


@pytest.mark.parametrize(
    "how",
    [
        pytest.param([], id="closed-loop-commands"),
        pytest.param(["--trust-recording"], id="closed-loop-script"),
        pytest.param(["--mode", "open"], id="open-loop"),
    ],
)
def test_replay_live_serves_exactly_the_replays_recording(
    recorded: Path, tmp_path: Path, procs: list[AeroexecProcess], how: list[str]
) -> None:
    replayed = tmp_path / "replayed.mcap"
    proc = Live(
        ["replay", str(recorded), *how, *live_args(replayed, "--wait-viewer", "--speed", "8")]
    )
    procs.append(proc)
    client = FoxgloveClient(proc.url()).start()
    wait_for_topic(client, "/drone1/vehicle/state")
    # the replay's own session: its metadata, not the recorded run's
    params = client.parameters(["aeroexec/clock", "aeroexec/replay_of", "aeroexec/mission"])
    code, out, err = proc.finish()
    assert code == 0, err
    assert "no differences" in out
    client.wait_closed()  # the servers closed with the command
    assert_parity(client, replayed)
    if how == ["--mode", "open"]:
        assert params["aeroexec/clock"] == "replay"
        assert params["aeroexec/replay_of"] == "flight.mcap"
    elif how == ["--trust-recording"]:
        assert params["aeroexec/mission"] == "appendix_c.py"
    else:
        assert params["aeroexec/mission"] == "(mission/command stream)"


def test_a_live_replay_records_the_same_file_as_a_plain_replay(
    recorded: Path, tmp_path: Path
) -> None:
    live, plain = tmp_path / "live.mcap", tmp_path / "plain.mcap"
    proc = Live(["replay", str(recorded), *live_args(live, "--speed", "50")])
    code, _, err = proc.finish()
    assert code == 0, err
    assert aeroexec("replay", str(recorded), "-o", str(plain)).returncode == 0
    assert live.read_bytes() == plain.read_bytes()


@pytest.mark.parametrize("mode", ["closed", "open"])
def test_speed_paces_a_replay_to_the_wall_clock(recorded: Path, mode: str) -> None:
    """18.6 recorded seconds at 5x take 3.7 s or more (unpaced: well under a second of
    replay); the report is that of an unpaced replay."""
    started = time.monotonic()
    proc = aeroexec("replay", str(recorded), "--mode", mode, "--speed", "5", "-f", "json")
    took = time.monotonic() - started
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["recordings"][0]["equal"] is True
    assert took >= 18.6 / 5


def test_paced_keeps_a_flights_recorded_ticks_to_the_wall_clock() -> None:
    """A flight's replay steps on its recorded ticks (`RecordedClock`): paced, it keeps
    them, the clock's own kind and its next tick (the command player reads it), and
    waits between them: 0.6 s of ticks at 2x take 0.3 s or more."""
    ticks = [100_000_000, 200_000_000, 700_000_000]
    clock = Paced(RecordedClock(iter(ticks)), speed=2.0)
    assert clock.kind == "replay" and clock.upcoming_ns() == ticks[0]
    started = time.monotonic()
    assert [clock.advance() for _ in ticks] == ticks
    assert time.monotonic() - started >= (ticks[-1] - ticks[0]) / 2 / 1e9
    assert clock.now_ns() == ticks[-1]


@pytest.mark.parametrize(
    "how",
    [pytest.param([], id="recorded-commands"), pytest.param(["--trust-recording"], id="script")],
)
def test_a_viewers_abort_stops_the_replay_and_is_recorded_as_an_abort(
    tmp_path: Path, procs: list[AeroexecProcess], how: list[str]
) -> None:
    mission = write_mission(tmp_path, PATROL)
    record = tmp_path / "patrol.mcap"
    assert aeroexec("run", str(mission), "-o", str(record), "-q").returncode == 0
    replayed = tmp_path / "replayed.mcap"
    proc = Live(
        ["replay", str(record), *how, *live_args(replayed, "--wait-viewer", "--speed", "5")]
    )
    procs.append(proc)
    client = FoxgloveClient(proc.url()).start()
    wait_for_topic(client, "/drone1/behavior_event")  # TAKE_OFF ended
    answer = client.call("/abort_mission", {})
    assert answer == {"ok": True, "action": "land"}
    code, out, err = proc.finish()
    assert code == 0, err  # a replay reports; without --check its differences are no failure
    assert "aborted by a live viewer" in out and "then inhibited" in out and "landing" in out
    client.wait_closed()
    recording = open_recording(replayed)
    assert recording.complete
    end = recording.metadata["aeroexec_end"]
    assert (end["reason"], end["detail"]) == ("abort", "aborted by a live viewer")
    assert_parity(client, replayed)
    states = [
        r.data
        for r in recording.records()
        if isinstance(r, RecordedTopic) and r.name == "vehicle/state"
    ]
    assert states[-1]["position"][2] == pytest.approx(0.0, abs=0.05)  # landed
    commands = [
        r.data
        for r in recording.records()
        if isinstance(r, RecordedTopic) and r.name == "mission/command"
    ]
    assert len(commands) < 40  # the rest of the patrol was not replayed


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["{rec}", "{rec}"], "--live serves one replay as it runs: give one recording (2 given)"),
        (
            ["{rec}", "-j", "2"],
            "--live serves one replay as it runs here, in this process: not with -j 2",
        ),
        (
            ["{rec}", "--executor", "ray"],
            "--live serves one replay as it runs here, in this process: not with --executor ray",
        ),
    ],
)
def test_what_one_live_view_cannot_show_is_one_line_and_exit_2(
    recorded: Path, args: list[str], message: str
) -> None:
    proc = aeroexec("replay", *(a.format(rec=recorded) for a in args), "--live", "--port", "0")
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [f"aeroexec replay: error: {message}"]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--wait-viewer"], "--port, --rerun-port and --wait-viewer are for --live: add --live"),
        (["--allow-remote"], "--allow-remote is for --live: add --live"),
        (["--speed", "-1"], "invalid value for --speed: -1: give a factor above 0"),
    ],
)
def test_live_options_without_live_are_one_line_and_exit_2(
    recorded: Path, args: list[str], message: str
) -> None:
    proc = aeroexec("replay", str(recorded), *args)
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [f"aeroexec replay: error: {message}"]


def test_one_signal_ends_a_live_replay_with_its_recording_finished(
    recorded: Path, tmp_path: Path, procs: list[AeroexecProcess]
) -> None:
    replayed = tmp_path / "replayed.mcap"
    proc = Live(["replay", str(recorded), *live_args(replayed, "--speed", "1")])
    procs.append(proc)
    url = proc.url()
    port = int(url.rsplit(":", 1)[1])
    client = FoxgloveClient(url).start()
    wait_for_topic(client, "/drone1/vehicle/state")  # the replay is under way, in real time
    started = time.monotonic()
    proc.popen.send_signal(signal.SIGTERM)
    code, _, err = proc.finish(timeout=10)
    assert time.monotonic() - started < 2.0
    assert code == 143, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "interrupted by SIGTERM" in lines[0], err
    client.wait_closed(10)
    recording = open_recording(replayed)
    assert recording.complete
    assert recording.metadata["aeroexec_end"]["reason"] == "interrupted"
    with socket.socket() as s, pytest.raises(ConnectionRefusedError):
        s.connect(("127.0.0.1", port))
