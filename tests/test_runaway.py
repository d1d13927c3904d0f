"""Runaway user code: one signal, or `--timeout`, ends every command promptly.

A mission or a behaviors module may never reach a safe point (`while True: pass`,
`time.sleep(1e6)`, a loop at module top level) or catch the `Interrupted` it is given
(`except BaseException: pass` in a loop). Each test runs `python -m aeroexec ...`, waits
until the user's code is busy (it writes a marker file first), sends ONE signal and
asserts: exit 128 + N within BOUND_S of the signal, exactly one stderr line, and a
recording finished with its end record and footer (`aeroexec info` reads it whole).
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from aeroexec import interrupts
from aeroexec.recording import open_recording

REPO = Path(__file__).resolve().parents[1]
CATALOG = REPO / "catalog" / "aerostack-2017.yaml"
#: The promise: the first signal ends any command within 2 s.
BOUND_S = 2.0
#: How long the user's code may take to get busy (a cold start on a loaded machine).
START_S = 60.0

PROLOGUE = """\
import os, pathlib, sys, time
import executive_engine_api as api

def busy():
    pathlib.Path({marker!r}).write_text(str(os.getpid()))
"""
#: name -> (text after PROLOGUE, the line (1-based, in the whole file) it loops on)
MISSIONS = {
    "spin": (
        "def runMission():\n"
        '    api.executeBehavior("TAKE_OFF")\n'
        "    busy()\n"
        "    while True:\n"
        "        pass\n",
        "while True:",
    ),
    "sleep": (
        'def runMission():\n    api.executeBehavior("TAKE_OFF")\n    busy()\n    time.sleep(1e6)\n',
        "time.sleep(1e6)",
    ),
    "top_level": (
        'api.executeBehavior("TAKE_OFF")\nbusy()\nwhile True:\n    pass\n\n'
        "def runMission():\n    pass\n",
        "while True:",
    ),
    "swallows": (
        "def runMission():\n"
        '    api.executeBehavior("TAKE_OFF")\n'
        "    busy()\n"
        "    while True:\n"
        "        try:\n"
        "            while True:\n"
        "                try:\n"
        '                    api.executeBehavior("WAIT", duration=1000)\n'
        "                except BaseException:\n"
        "                    pass\n"
        "        except BaseException:\n"
        "            pass\n",
        "",  # anywhere in its loop
    ),
}
LOOPING_MODULE = """\
import os, pathlib
pathlib.Path({marker!r}).write_text(str(os.getpid()))
while True:
    pass
"""


def write_mission(tmp_path: Path, kind: str) -> tuple[Path, Path]:
    marker = tmp_path / "busy.marker"
    text, _ = MISSIONS[kind]
    path = tmp_path / f"{kind}.py"
    path.write_text(PROLOGUE.format(marker=str(marker)) + text, encoding="utf-8")
    return path, marker


def line_of(path: Path, text: str) -> int:
    lines = path.read_text(encoding="utf-8").splitlines()
    return next(i for i, line in enumerate(lines, 1) if line.strip() == text)


def start(*args: str, cwd: Path) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "aeroexec", *args],
        cwd=cwd,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )


def aeroexec(*args: str, cwd: Path = REPO) -> subprocess.CompletedProcess[str]:
    """`python -m aeroexec ARGS`, to its end (within a minute)."""
    return subprocess.run(
        [sys.executable, "-m", "aeroexec", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )


def busy(process: subprocess.Popen[str], marker: Path) -> None:
    deadline = time.monotonic() + START_S
    while not marker.exists():
        assert process.poll() is None, f"ended before it was busy: {process.communicate()[1]}"
        assert time.monotonic() < deadline, "never got busy"
        time.sleep(0.01)
    time.sleep(0.2)  # well inside its loop


def stop_once(process: subprocess.Popen[str], signum: int) -> tuple[float, str]:
    """Send `signum` once; (seconds until the process ended, its stderr)."""
    sent = time.monotonic()
    process.send_signal(signum)
    try:
        _, err = process.communicate(timeout=BOUND_S + 10)
    except subprocess.TimeoutExpired:
        process.kill()
        _, err = process.communicate()
        pytest.fail(f"still running {BOUND_S + 10:g} s after one {signal.Signals(signum).name}")
    return time.monotonic() - sent, err


def one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    return lines[0]


def finished(path: Path, reason: str, detail: str) -> None:
    recording = open_recording(path)
    assert recording.complete, recording.problem
    end = recording.metadata["aeroexec_end"]
    assert (end["reason"], end["detail"]) == (reason, detail)
    info = aeroexec("info", str(path))
    assert info.returncode == 0, info.stderr
    assert re.search(r"^complete:\s+yes$", info.stdout, re.M), info.stdout
    assert info.stderr == ""


# -- one signal --------------------------------------------------------------------------
@pytest.mark.parametrize("kind", sorted(MISSIONS))
def test_one_sigterm_ends_a_mission_that_never_yields(tmp_path: Path, kind: str) -> None:
    script, marker = write_mission(tmp_path, kind)
    out = tmp_path / "flight.mcap"
    process = start("run", str(script), "-q", "-o", str(out), cwd=tmp_path)
    busy(process, marker)
    took, err = stop_once(process, signal.SIGTERM)
    assert process.returncode == 128 + signal.SIGTERM, err
    line = one_line(err)
    assert line.startswith("aeroexec run: interrupted by SIGTERM; recording finalized: "), line
    assert took <= BOUND_S, f"{took:.2f} s"
    finished(out, "interrupted", "SIGTERM")


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGHUP])
def test_the_first_sigint_or_sighup_is_enough_too(tmp_path: Path, signum: int) -> None:
    script, marker = write_mission(tmp_path, "spin")
    out = tmp_path / "flight.mcap"
    process = start("run", str(script), "-q", "-o", str(out), cwd=tmp_path)
    busy(process, marker)
    took, err = stop_once(process, signum)
    assert process.returncode == 128 + signum, err
    assert one_line(err).startswith(f"aeroexec run: interrupted by {signal.Signals(signum).name}")
    assert took <= BOUND_S, f"{took:.2f} s"
    finished(out, "interrupted", signal.Signals(signum).name)


def test_a_mission_that_keeps_catching_the_signal_is_ended_with_its_recording(
    tmp_path: Path,
) -> None:
    """The last resort: the recording is finished from the signal handler, then exit."""
    script, marker = write_mission(tmp_path, "swallows")
    out = tmp_path / "flight.mcap"
    process = start("run", str(script), "-q", "-o", str(out), cwd=tmp_path)
    busy(process, marker)
    took, err = stop_once(process, signal.SIGINT)
    assert process.returncode == 130, err
    line = one_line(err)
    assert "recording finalized" in line and "exited without unwinding" in line, line
    assert took <= BOUND_S, f"{took:.2f} s"
    finished(out, "interrupted", "SIGINT")


@pytest.mark.parametrize("kind", ["spin", "swallows"])
def test_replay_workers_stop_a_runaway_mission_at_one_signal(tmp_path: Path, kind: str) -> None:
    recorded = tmp_path / "recorded.mcap"
    assert aeroexec("run", "missions/appendix_c.py", "-q", "-o", str(recorded)).returncode == 0
    inputs = tmp_path / "in"
    inputs.mkdir()
    for name in ("a.mcap", "b.mcap"):
        (inputs / name).write_bytes(recorded.read_bytes())
    script, marker = write_mission(tmp_path, kind)
    out_dir = tmp_path / "out"
    process = start(
        "replay", str(inputs), "--mission", str(script), "-j", "2", "--output-dir", str(out_dir),
        cwd=tmp_path,
    )  # fmt: skip
    busy(process, marker)
    took, err = stop_once(process, signal.SIGTERM)  # the parent alone, as a CI timeout does
    assert process.returncode == 143, err
    assert one_line(err).startswith("aeroexec replay: interrupted by SIGTERM"), err
    assert took <= BOUND_S, f"{took:.2f} s"
    written = sorted(out_dir.glob("*.mcap"))
    assert written, "no replay was under way"
    for path in written:
        finished(path, "interrupted", "SIGTERM")


# -- behaviors modules that loop at import --------------------------------------------------
@pytest.mark.parametrize("command", ["verify", "run"])
def test_a_behaviors_module_looping_at_import_stops_at_one_signal(
    tmp_path: Path, command: str
) -> None:
    marker = tmp_path / "busy.marker"
    module = tmp_path / "loopy.py"
    module.write_text(LOOPING_MODULE.format(marker=str(marker)), encoding="utf-8")
    target = str(CATALOG) if command == "verify" else str(REPO / "missions" / "appendix_c.py")
    process = start(command, target, "-b", str(module), cwd=tmp_path)
    busy(process, marker)
    took, err = stop_once(process, signal.SIGTERM)
    assert process.returncode == 143, err
    assert one_line(err) == f"aeroexec {command}: interrupted by SIGTERM"
    assert took <= BOUND_S, f"{took:.2f} s"


@pytest.mark.parametrize("command", ["verify", "run"])
def test_timeout_ends_a_behaviors_import_at_its_line(tmp_path: Path, command: str) -> None:
    module = tmp_path / "loopy.py"
    module.write_text(LOOPING_MODULE.format(marker=str(tmp_path / "m")), encoding="utf-8")
    target = str(CATALOG) if command == "verify" else str(REPO / "missions" / "appendix_c.py")
    done = aeroexec(command, target, "-b", str(module), "--timeout", "1", cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    line = one_line(done.stderr)
    assert re.fullmatch(
        r"loopy\.py:[34]:1: error: importing --behaviors \S*loopy\.py failed: "
        r"still running after 1 s of wall-clock time \(--timeout\)",
        line,
    ), line


# -- the wall-clock limit ---------------------------------------------------------------------
@pytest.mark.parametrize("kind", sorted(MISSIONS))
def test_timeout_fails_the_mission_at_its_file_and_line(tmp_path: Path, kind: str) -> None:
    script, _ = write_mission(tmp_path, kind)
    out = tmp_path / "flight.mcap"
    started = time.monotonic()
    done = aeroexec("run", script.name, "-q", "-o", str(out), "--timeout", "1", cwd=tmp_path)
    took = time.monotonic() - started
    assert done.returncode == 1, done.stderr
    line = one_line(done.stderr)
    looping = MISSIONS[kind][1]
    at = rf"{script.name}:{line_of(script, looping)}" if looping else rf"{script.name}:\d+"
    assert re.match(
        rf"{at}: mission stopped: still running after 1 s of wall-clock time \(--timeout\)", line
    ), line
    assert took < 1 + 1 + 20  # the limit, the forced exit's grace, a cold start
    finished(out, "timeout", "still running after 1 s of wall-clock time (--timeout)")


def test_timeout_in_a_closed_loop_replay(tmp_path: Path) -> None:
    recorded = tmp_path / "recorded.mcap"
    assert aeroexec("run", "missions/appendix_c.py", "-q", "-o", str(recorded)).returncode == 0
    script, _ = write_mission(tmp_path, "sleep")
    done = aeroexec(
        "replay", str(recorded), "--mission", script.name, "--timeout", "1", cwd=tmp_path
    )
    assert "still running after 1 s of wall-clock time (--timeout)" in done.stdout + done.stderr
    assert f"{script.name}:{line_of(script, 'time.sleep(1e6)')}" in done.stdout + done.stderr


def test_a_mission_that_returns_is_not_limited_by_a_generous_timeout(tmp_path: Path) -> None:
    done = aeroexec("run", "missions/appendix_c.py", "-q", "--timeout", "600")
    assert done.returncode == 0, done.stderr


# -- sys.exit and os._exit in the user's code -------------------------------------------------
def test_sys_exit_in_a_behaviors_module_is_a_plugin_failure_at_its_line(tmp_path: Path) -> None:
    module = tmp_path / "exits.py"
    module.write_text("import sys\n\nsys.exit(7)\n", encoding="utf-8")
    for command, target in (("verify", CATALOG), ("run", REPO / "missions" / "appendix_c.py")):
        done = aeroexec(command, str(target), "-b", "exits.py", cwd=tmp_path)
        assert done.returncode == 2, (command, done.stderr)
        assert one_line(done.stderr) == (
            "exits.py:3:1: error: importing --behaviors exits.py failed: sys.exit(7)"
        )


@pytest.mark.parametrize(
    ("call", "code", "says"),
    [
        ("sys.exit(7)", 1, "mission failed: the mission called sys.exit(7)"),
        ("sys.exit('bye')", 1, "mission failed: the mission called sys.exit('bye')"),
        ("sys.exit(0)", 0, ""),
        ("sys.exit()", 0, ""),
    ],
)
def test_sys_exit_in_a_mission(tmp_path: Path, call: str, code: int, says: str) -> None:
    script = tmp_path / "exits.py"
    script.write_text(
        "import sys\nimport executive_engine_api as api\n\ndef runMission():\n"
        f'    api.executeBehavior("TAKE_OFF")\n    {call}\n',
        encoding="utf-8",
    )
    done = aeroexec("run", "exits.py", "-q", "-o", "f.mcap", cwd=tmp_path)
    assert done.returncode == code, done.stderr
    if says:
        assert one_line(done.stderr) == f"exits.py:6: {says}"
    else:
        assert done.stderr == ""
    assert open_recording(tmp_path / "f.mcap").metadata["aeroexec_end"]["reason"] == "exited"


def test_os_exit_leaves_a_recording_info_calls_unfinished_and_recover_completes(
    tmp_path: Path,
) -> None:
    """What no handler can catch (documented in docs/recording.md): the recording has
    no footer; `info` says so, `recover` makes a complete copy of everything flushed."""
    script = tmp_path / "quits.py"
    script.write_text(
        "import os\nimport executive_engine_api as api\n\ndef runMission():\n"
        '    api.executeBehavior("TAKE_OFF")\n    api.executeBehavior("WAIT", duration=5)\n'
        "    os._exit(0)\n",
        encoding="utf-8",
    )
    out = tmp_path / "f.mcap"
    run = aeroexec("run", "quits.py", "-q", "-o", str(out), cwd=tmp_path)
    assert run.returncode == 0  # os._exit(0): the process is gone before aeroexec can say
    assert not open_recording(out).complete
    info = aeroexec("info", str(out))
    assert re.search(r"^complete:\s+NO: no footer", info.stdout, re.M), info.stdout
    assert "incomplete recording" in info.stderr and "aeroexec recover" in info.stderr
    fixed = tmp_path / "fixed.mcap"
    recover = aeroexec("recover", str(out), "-o", str(fixed))
    assert recover.returncode == 0, recover.stderr
    whole = open_recording(fixed)
    assert whole.complete, whole.problem
    assert whole.survey().message_count == open_recording(out).survey().message_count > 0
    assert os.path.getsize(fixed) > 0


# -- the watchdog never cuts a record in half -------------------------------------------------
CRITICAL = """\
import time

def write_for(seconds, trace):
    trace.append("entered")
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        pass
    trace.append("left")
"""


def test_the_watchdog_waits_until_the_main_thread_leaves_a_critical_file(tmp_path: Path) -> None:
    """As the recorder's module is: a signal due while the main thread is inside it is
    raised only once it has left (in-process: the watchdog is this process's)."""
    path = tmp_path / "critical_writer.py"
    path.write_text(CRITICAL, encoding="utf-8")
    namespace: dict[str, object] = {}
    exec(compile(CRITICAL, str(path), "exec"), namespace)
    write_for = namespace["write_for"]
    assert callable(write_for)
    trace: list[str] = []
    interrupts.critical_file(str(path))
    try:
        with (
            interrupts.signals_as_interrupts(),
            pytest.raises(interrupts.Interrupted) as caught,
            interrupts.user_code(forced_exit=False),
        ):
            os.kill(os.getpid(), signal.SIGTERM)
            # Past the grace inside the critical file, then spinning outside it.
            write_for(interrupts.GRACE_S + 0.4, trace)
            left = time.monotonic()
            trace.append("spinning")
            while True:
                pass
    finally:
        interrupts._critical_files.discard(str(path))
    assert caught.value.signum == signal.SIGTERM
    assert trace == ["entered", "left", "spinning"]
    assert time.monotonic() - left < 0.5  # raised soon after it left
    assert interrupts.pending() is None


def test_recorder_writes_are_critical() -> None:
    from aeroexec.recording import writer

    assert writer.__file__ in interrupts._critical_files


# -- a behavior that never returns, during the session ----------------------------------------
RUNAWAY_BEHAVIOR = """\
import pathlib, time
from aeroexec.executive import Behavior

class StuckWait(Behavior):
    name = "WAIT"
    argument_names = ("DURATION",)

    def on_run(self):
        pathlib.Path({marker!r}).write_text("stuck")
        while True:
            try:
                time.sleep(1000)
            except BaseException:
                pass
"""


def test_a_behavior_stuck_in_its_own_loop_stops_at_one_signal(tmp_path: Path) -> None:
    marker = tmp_path / "busy.marker"
    module = tmp_path / "stuck.py"
    module.write_text(RUNAWAY_BEHAVIOR.format(marker=str(marker)), encoding="utf-8")
    mission = tmp_path / "waits.py"
    mission.write_text(
        "import executive_engine_api as api\n\ndef runMission():\n"
        '    api.executeBehavior("TAKE_OFF")\n    api.executeBehavior("WAIT", duration=1)\n',
        encoding="utf-8",
    )
    out = tmp_path / "flight.mcap"
    process = start("run", str(mission), "-b", str(module), "-q", "-o", str(out), cwd=tmp_path)
    busy(process, marker)
    took, err = stop_once(process, signal.SIGHUP)
    assert process.returncode == 128 + signal.SIGHUP, err
    assert one_line(err).startswith("aeroexec run: interrupted by SIGHUP; recording finalized")
    assert took <= BOUND_S, f"{took:.2f} s"
    finished(out, "interrupted", "SIGHUP")
