"""SIGINT, SIGTERM and SIGHUP on every command that writes a file, with real processes.

Each command is started as `python -m aeroexec ...`, given the signal once it is busy
(a marker file its mission writes, or its partial output appearing), and must then:
finish its output (a recording gets its end record and footer) or remove the partial
one, say which in one stderr line, and exit 128 + signal.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from aeroexec.mission.session import SessionConfig, simulate
from aeroexec.recording import open_recording

REPO = Path(__file__).resolve().parents[1]
BAG = REPO / "tests" / "fixtures" / "bags" / "aerostack_2017_first_view_ros1.bag"
WAIT_S = 60.0

#: Takes off, says so (a marker file per process), then waits for a simulated day.
BUSY = """\
import os, pathlib
import executive_engine_api as api

def runMission():
    api.executeBehavior("TAKE_OFF")
    pathlib.Path({markers!r}, str(os.getpid())).write_text("flying")
    while True:
        api.executeBehavior("WAIT", duration=1000)
"""
#: Spins in its own loop: never reaches a safe point.
SPIN = """\
import os, pathlib
import executive_engine_api as api

def runMission():
    api.executeBehavior("TAKE_OFF")
    pathlib.Path({markers!r}, str(os.getpid())).write_text("spinning")
    while True:
        pass
"""
#: A long, big recording (hours of hovering on an endless battery) for the readers.
ENDLESS_WORLD = "name: endless\nseed: 0\nbattery:\n  flight_endurance: 100000\n"
LONG = """\
import executive_engine_api as api

def runMission():
    api.executeBehavior("TAKE_OFF")
    for _ in range(4):
        api.executeBehavior("KEEP_HOVERING", duration=1000)
    api.executeBehavior("LAND")
"""


def start(*args: str, cwd: Path) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "aeroexec", *args],
        cwd=cwd,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )


def when(condition: Callable[[], bool], process: subprocess.Popen[str]) -> None:
    deadline = time.monotonic() + WAIT_S
    while not condition():
        assert process.poll() is None, f"ended before it was busy: {process.communicate()[1]}"
        assert time.monotonic() < deadline, "never got busy"
        time.sleep(0.01)


def stopped(process: subprocess.Popen[str], signum: int) -> str:
    """Send `signum`; the one stderr line, after checking the exit code."""
    process.send_signal(signum)
    _, err = process.communicate(timeout=WAIT_S)
    assert process.returncode == 128 + signum, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    name = signal.Signals(signum).name
    assert re.match(rf"aeroexec [a-z]+: interrupted by {name}\b", lines[0]), err
    return lines[0]


def mission(directory: Path, template: str) -> tuple[Path, Path]:
    markers = directory / "markers"
    markers.mkdir(exist_ok=True)
    path = directory / "busy.py"
    path.write_text(template.format(markers=str(markers)), encoding="utf-8")
    return path, markers


def finalized(path: Path, signum: int) -> None:
    recording = open_recording(path)
    assert recording.complete, recording.problem
    end = recording.metadata["aeroexec_end"]
    assert (end["reason"], end["detail"]) == ("interrupted", signal.Signals(signum).name)
    assert recording.survey().message_count > 0


@pytest.fixture(scope="module")
def long_recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    directory = tmp_path_factory.mktemp("signals")
    world = directory / "endless.yaml"
    world.write_text(ENDLESS_WORLD, encoding="utf-8")
    script = directory / "long.py"
    script.write_text(LONG, encoding="utf-8")
    path = directory / "long.mcap"
    simulate(SessionConfig(mission=script, world=world, record=path))
    return path


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
def test_run_record_is_finalized(tmp_path: Path, signum: int) -> None:
    script, markers = mission(tmp_path, BUSY)
    out = tmp_path / "flight.mcap"
    process = start("run", str(script), "-q", "-o", str(out), cwd=tmp_path)
    when(lambda: any(markers.iterdir()), process)
    line = stopped(process, signum)
    assert f"recording finalized: {out} (" in line and "messages, complete)" in line
    finalized(out, signum)


def test_a_mission_spinning_in_its_own_loop_stops_at_the_first_signal(tmp_path: Path) -> None:
    """No safe point ever comes: the watchdog raises the signal in the mission's loop
    (tests/test_runaway.py holds the other runaway kinds and the time bound)."""
    script, markers = mission(tmp_path, SPIN)
    out = tmp_path / "spin.mcap"
    process = start("run", str(script), "-q", "-o", str(out), cwd=tmp_path)
    when(lambda: any(markers.iterdir()), process)
    line = stopped(process, signal.SIGINT)
    assert "recording finalized" in line
    finalized(out, signal.SIGINT)


def test_replay_output_is_finalized(tmp_path: Path, long_recording: Path) -> None:
    script, markers = mission(tmp_path, BUSY)
    out = tmp_path / "replay.mcap"
    process = start(
        "replay", str(long_recording), "--mission", str(script), "-o", str(out), cwd=tmp_path
    )
    when(lambda: any(markers.iterdir()), process)
    line = stopped(process, signal.SIGTERM)
    assert f"recording finalized: {out} (" in line
    finalized(out, signal.SIGTERM)


def test_replay_jobs_pass_the_signal_to_their_workers(tmp_path: Path, long_recording: Path) -> None:
    script, markers = mission(tmp_path, BUSY)
    inputs = tmp_path / "in"
    inputs.mkdir()
    for name in ("a.mcap", "b.mcap"):
        (inputs / name).write_bytes(long_recording.read_bytes())
    out_dir = tmp_path / "out"
    process = start(
        "replay",
        str(inputs),
        "--mission",
        str(script),
        "--jobs",
        "2",
        "--output-dir",
        str(out_dir),
        cwd=tmp_path,
    )
    when(lambda: len(list(markers.iterdir())) == 2, process)  # both workers busy
    os.kill(process.pid, signal.SIGTERM)  # the parent alone, as a CI timeout may do
    line = stopped(process, signal.SIGTERM)
    for name in ("a.mcap", "b.mcap"):
        assert f"recording finalized: {out_dir / name}" in line
        finalized(out_dir / name, signal.SIGTERM)


def test_view_save_removes_its_partial_file(tmp_path: Path, long_recording: Path) -> None:
    out = tmp_path / "flight.rrd"
    partial = tmp_path / ".flight.rrd.partial"
    process = start("view", str(long_recording), "--output", str(out), cwd=tmp_path)
    when(partial.exists, process)
    line = stopped(process, signal.SIGHUP)
    assert line.endswith(f"the partial output was removed, {out} not written")
    assert not out.exists() and not partial.exists()


def test_recover_removes_its_partial_file(tmp_path: Path, long_recording: Path) -> None:
    out = tmp_path / "fixed.mcap"
    partial = tmp_path / ".fixed.mcap.partial"
    process = start("recover", str(long_recording), "-o", str(out), cwd=tmp_path)
    when(partial.exists, process)
    line = stopped(process, signal.SIGTERM)
    assert line.endswith(f"the partial output was removed, {out} not written")
    assert not out.exists() and not partial.exists()


def test_import_removes_its_partial_file(tmp_path: Path) -> None:
    out = tmp_path / "flight.mcap"
    partial = tmp_path / ".flight.mcap.partial"
    process = start("import", str(BAG), "-o", str(out), cwd=tmp_path)
    when(partial.exists, process)
    line = stopped(process, signal.SIGINT)
    assert line.endswith(f"the partial output was removed, {out} not written")
    assert not out.exists() and not partial.exists()


def test_explore_keeps_its_violations_whole_and_names_what_stays(tmp_path: Path) -> None:
    out = tmp_path / "whatif"
    process = start(
        "explore",
        str(REPO / "recordings" / "appendix_c-v0.1.0.mcap"),
        "--trust-recording",
        "--offsets",
        "0,0.5,1,1.5,2,3,4,5",
        "--output-dir",
        str(out),
        cwd=tmp_path,
    )
    when(lambda: out.exists() and any(out.glob("*.mcap")), process)  # a violation kept
    line = stopped(process, signal.SIGTERM)
    # The runs in flight were finalized in a scratch folder that is gone by now: the
    # line names what stays, not a file the user cannot find.
    assert ".explore-" not in line, line
    match = re.search(r"(\d+) of (\d+) runs done, (\d+) violating run\(s\) kept in (.+)$", line)
    assert match, line
    done, total, kept = (int(match[i]) for i in (1, 2, 3))
    assert 0 < done < total and match[4] == str(out)
    left = sorted(p.name for p in out.iterdir())
    assert len(left) == kept and all(name.endswith(".mcap") for name in left), left
    for path in out.glob("*.mcap"):
        assert open_recording(path).complete, path


def test_fuzz_keeps_every_failing_mission_it_found(tmp_path: Path) -> None:
    out = tmp_path / "fuzz"
    catalog = REPO / "aeroexec" / "data" / "catalog" / "default.yaml"
    base = ("fuzz", str(catalog), "--seed", "1", "--output-dir", str(out))
    process = start(*base, "--budget", "600s", cwd=tmp_path)
    database = out / "failures.json"
    when(database.exists, process)  # saved as soon as the search found something
    line = stopped(process, signal.SIGTERM)
    match = re.search(r"the (\d+) failing mission\(s\) found so far are in (\S+):", line)
    assert match and match[2] == str(database), line
    saved = json.loads(database.read_text(encoding="utf-8"))["missions"]
    assert len(saved) == int(match[1]) > 0
    # The next run starts with them and writes each one up.
    again = subprocess.run(
        [sys.executable, "-m", "aeroexec", *base, "--budget", "1"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=WAIT_S,
    )
    assert again.returncode == 1, again.stderr
    written = {p.name.split("-", 1)[1] for p in out.iterdir() if p.is_dir()}
    assert written == {entry["property"] for entry in saved}
