"""JUnit reports of `replay` and `diff` for CI test-report tools: every testcase names
its recording in `file` (GitHub's test-report actions annotate that file, else they guess
from `classname`) and its duration in `time`; the suite has a `timestamp` (UTC) and a
`time`. With SOURCE_DATE_EPOCH set, the report is reproducible: that timestamp, every
duration 0, the same bytes for the same results."""

from __future__ import annotations

import re
import shutil
import time
import xml.etree.ElementTree as ET
from datetime import UTC, datetime
from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.mission import APPENDIX_C, SessionConfig, simulate
from aeroexec.replay import ReplayResult
from aeroexec.replay.report import replay_junit, start_timing

ISO = re.compile(r"^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d$")  # JUnit's xs:dateTime, no zone


@pytest.fixture(scope="module")
def flights(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("junit")
    simulate(SessionConfig(mission=APPENDIX_C, record=folder / "a.mcap"))
    shutil.copyfile(folder / "a.mcap", folder / "b.mcap")
    (folder / "c.mcap").write_bytes(b"\x89MCAP0\r\nbroken")
    return folder


def _cli(*args: str, env: dict[str, str] | None = None) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, list(args), env=env)
    return result.exit_code, result.stdout, result.stderr


def test_replay_testcases_name_their_recording_and_duration(flights: Path) -> None:
    before = datetime.now(UTC).replace(microsecond=0, tzinfo=None)
    code, out, _ = _cli(
        "replay",
        str(flights),
        "--format",
        "junit",
        env={"SOURCE_DATE_EPOCH": None},  # type: ignore[dict-item]
    )
    after = datetime.now(UTC).replace(tzinfo=None)
    assert code == 2  # c.mcap is unreadable
    suite = ET.fromstring(out)
    cases = suite.findall("testcase")
    assert [c.get("file") for c in cases] == [
        str(flights / n) for n in ("a.mcap", "b.mcap", "c.mcap")
    ]
    assert [c.get("name") for c in cases] == [c.get("file") for c in cases]
    durations = [float(c.get("time", "")) for c in cases]
    assert durations[0] > 0 and durations[1] > 0  # a closed-loop replay takes time
    stamp = suite.get("timestamp", "")
    assert ISO.match(stamp)
    assert before <= datetime.fromisoformat(stamp) <= after
    assert float(suite.get("time", "")) >= max(durations)
    assert cases[2].find("error") is not None


def test_diff_testcase_is_attached_to_the_new_recording(flights: Path) -> None:
    code, out, _ = _cli(
        "diff", str(flights / "a.mcap"), str(flights / "b.mcap"), "--format", "junit"
    )
    assert code == 0
    suite = ET.fromstring(out)
    (case,) = suite.findall("testcase")
    assert case.get("file") == str(flights / "b.mcap")
    assert float(case.get("time", "")) > 0
    assert ISO.match(suite.get("timestamp", ""))


def test_source_date_epoch_makes_the_report_reproducible(flights: Path) -> None:
    env = {"SOURCE_DATE_EPOCH": "1700000000"}
    args = ("replay", str(flights / "a.mcap"), str(flights / "b.mcap"), "--format", "junit")
    code, first, _ = _cli(*args, env=env)
    assert code == 0
    suite = ET.fromstring(first)
    assert suite.get("timestamp") == "2023-11-14T22:13:20"
    assert suite.get("time") == "0.000"
    assert {c.get("time") for c in suite.findall("testcase")} == {"0.000"}
    time.sleep(1.1)  # another second on the clock: nothing in the report may show it
    assert _cli(*args, env=env)[1] == first
    code, out, _ = _cli(
        "diff", str(flights / "a.mcap"), str(flights / "b.mcap"), "--format", "junit", env=env
    )
    assert code == 0 and 'timestamp="2023-11-14T22:13:20"' in out and 'time="0.000"' in out


def test_a_malformed_source_date_epoch_is_an_error_for_junit_only(flights: Path) -> None:
    env = {"SOURCE_DATE_EPOCH": "yesterday"}
    code, out, err = _cli("replay", str(flights / "a.mcap"), "--format", "junit", env=env)
    assert code == 2 and out == ""
    assert err == (
        "aeroexec replay: error: SOURCE_DATE_EPOCH must be whole seconds since 1970, got "
        "'yesterday'\n"
    )
    assert _cli("replay", str(flights / "a.mcap"), env=env)[0] == 0  # text needs no clock


def test_timing_units() -> None:
    timing = start_timing({}, now=0.5)
    assert timing.timestamp == "1970-01-01T00:00:00" and not timing.reproducible
    assert timing.duration(1.23456) == "1.235" and timing.duration(None) == "0.000"
    fixed = start_timing({"SOURCE_DATE_EPOCH": "86400"}, now=5.0)
    assert fixed.timestamp == "1970-01-02T00:00:00" and fixed.duration(3.0) == "0.000"
    # Equal results compare equal however long they took (parallel and serial batches).
    assert ReplayResult("x", seconds=1.0) == ReplayResult("x", seconds=2.0)
    xml = replay_junit([ReplayResult("x.mcap", error="no", seconds=0.25)], timing=timing)
    assert '<testcase classname="aeroexec.replay" name="x.mcap" file="x.mcap" time="0.250">' in xml
