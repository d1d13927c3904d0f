"""Outputs on a full disk: one line, exit code 2, and what was kept or removed.

Two real, unprivileged ways to run out of room: `/dev/full` (every write fails with
ENOSPC) and a file size limit (`RLIMIT_FSIZE`, writes past it fail with EFBIG) set in the
child process, which makes a file fill up part-way like a small filesystem does.
"""

from __future__ import annotations

import resource
import subprocess
import sys
from pathlib import Path

import pytest

from aeroexec.mission.session import SessionConfig, simulate
from aeroexec.recording import open_recording

REPO = Path(__file__).resolve().parents[1]
MISSION = REPO / "missions" / "appendix_c.py"
BAG = REPO / "tests" / "fixtures" / "bags" / "ros1_turtlesim_example_lz4.bag"
LIMIT = 40_000  # bytes: the Appendix C recording is ~100 kB


def aeroexec(*args: str, cwd: Path, limit: int | None = None) -> tuple[int, str]:
    def small_disk() -> None:
        if limit is not None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    result = subprocess.run(
        [sys.executable, "-m", "aeroexec", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        check=False,
        preexec_fn=small_disk,
        timeout=120,
    )
    return result.returncode, result.stderr


def one_line(stderr: str) -> str:
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert len(lines) == 1, stderr
    assert "Traceback" not in stderr
    return lines[0]


@pytest.fixture(scope="module")
def full_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("full") / "whole.mcap"
    simulate(SessionConfig(mission=MISSION, record=path))
    return path


def test_record_to_dev_full(tmp_path: Path) -> None:
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full here")
    code, err = aeroexec("run", str(MISSION), "-q", "-o", "/dev/full", cwd=tmp_path)
    assert code == 2
    assert (
        one_line(err) == "/dev/full: error: cannot write: No space left on device; nothing was kept"
    )


@pytest.mark.parametrize("command", ["run", "replay"])
def test_a_recording_that_fills_the_disk_keeps_its_last_flush(
    tmp_path: Path, full_run: Path, command: str
) -> None:
    out = tmp_path / "cut.mcap"
    if command == "run":
        args = ["run", str(MISSION), "-q", "-o", str(out)]
    else:
        args = ["replay", str(full_run), "--mission", str(MISSION), "-o", str(out)]
    code, err = aeroexec(*args, cwd=tmp_path, limit=LIMIT)
    assert code == 2
    line = one_line(err)
    assert line.startswith(f"{out}: error: cannot write: File too large; kept the first ")
    kept = int(line.split("kept the first ")[1].split()[0])
    assert "readable without a footer" in line
    # What it says was kept is there, readable, and is the start of the whole run.
    cut = open_recording(out)
    assert not cut.complete and out.stat().st_size <= LIMIT
    messages = [(m.channel.topic, m.log_time_ns, m.data) for m in cut.messages()]
    assert len(messages) == kept > 0
    whole = [(m.channel.topic, m.log_time_ns, m.data) for m in open_recording(full_run).messages()]
    assert messages == whole[:kept]
    assert "file ends at byte" in (cut.problem or "")  # cut at a flush: no partial chunk


@pytest.mark.parametrize("command", ["recover", "import", "view"])
def test_whole_file_outputs_are_removed_when_the_disk_fills(
    tmp_path: Path, full_run: Path, command: str
) -> None:
    if command == "recover":
        out = tmp_path / "fixed.mcap"
        args = ["recover", str(full_run), "-o", str(out)]
        limit = 20_000
    elif command == "import":
        out = tmp_path / "bag.mcap"
        args = ["import", str(BAG), "-o", str(out)]
        limit = 50_000
    else:
        out = tmp_path / "flight.rrd"
        args = ["view", str(full_run), "--output", str(out)]
        limit = 20_000
    code, err = aeroexec(*args, cwd=tmp_path, limit=limit)
    assert code == 2, err
    line = one_line(err)
    assert line.startswith(f"{out}: error: cannot write: ")
    assert line.endswith("the partial output was removed")
    assert not out.exists()
    assert [p.name for p in tmp_path.iterdir()] == []  # no partial file either
