"""JUnit reports of `replay` and `diff` for CI test-report tools: a `<testsuites>` root;
every testcase is named by its recording and points, in `file` and `line`, at the mission
script's line of its first difference (test-report actions annotate that, not a binary
.mcap), and has its duration in `time`; the suite has a `timestamp` (UTC) and a `time`.
With SOURCE_DATE_EPOCH set, the report is reproducible: that timestamp, every duration
0, the same bytes for the same results."""

from __future__ import annotations

import json
import re
import shutil
import time
import xml.etree.ElementTree as ET
from datetime import UTC, datetime
from pathlib import Path

import pytest
from test_replay_support import catalog_for
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
    suite = _suite(out)
    cases = suite.findall("testcase")
    assert [c.get("name") for c in cases] == [
        str(flights / n) for n in ("a.mcap", "b.mcap", "c.mcap")
    ]
    # The mission as the recording names it (its file name) for the replayed ones, the
    # recording for the unreadable one; no line without a difference.
    assert [c.get("file") for c in cases] == [
        APPENDIX_C.name,
        APPENDIX_C.name,
        cases[2].get("name"),
    ]
    assert [c.get("line") for c in cases] == [None, None, None]
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
    suite = _suite(out)
    (case,) = suite.findall("testcase")
    assert case.get("name") == f"{flights / 'a.mcap'} -> {flights / 'b.mcap'}"
    assert case.get("file") == APPENDIX_C.name and case.get("line") is None
    assert float(case.get("time", "")) > 0
    assert ISO.match(suite.get("timestamp", ""))


def test_source_date_epoch_makes_the_report_reproducible(flights: Path) -> None:
    env = {"SOURCE_DATE_EPOCH": "1700000000"}
    args = ("replay", str(flights / "a.mcap"), str(flights / "b.mcap"), "--format", "junit")
    code, first, _ = _cli(*args, env=env)
    assert code == 0
    suite = _suite(first)
    assert suite.get("timestamp") == "2023-11-14T22:13:20"
    assert suite.get("time") == "0.000"
    assert {c.get("time") for c in suite.findall("testcase")} == {"0.000"}
    time.sleep(1.1)  # another second on the clock: nothing in the report may show it
    assert _cli(*args, env=env)[1] == first
    code, out, _ = _cli(
        "diff", str(flights / "a.mcap"), str(flights / "b.mcap"), "--format", "junit", env=env
    )
    assert code == 0 and 'timestamp="2023-11-14T22:13:20"' in out and 'time="0.000"' in out


def _suite(xml: str) -> ET.Element:
    """The one testsuite of a report, under its `<testsuites>` root with the same totals."""
    root = ET.fromstring(xml)
    assert root.tag == "testsuites"
    (suite,) = root.findall("testsuite")
    for total in ("name", "tests", "failures", "errors", "skipped", "time", "timestamp"):
        assert root.get(total) == suite.get(total), total
    return suite


#: The line of the Appendix C mission that flies to (3, 5.5, 1.3): the command a catalog
#: whose GO_TO_POINT allows [-2, 2] only rejects, the first difference.
FAR_POINT = next(
    number
    for number, text in enumerate(APPENDIX_C.read_text(encoding="utf-8").splitlines(), 1)
    if "coordinates=[3, 5.5, 1.3]" in text
)


def test_a_difference_points_at_its_line_of_the_mission(flights: Path, tmp_path: Path) -> None:
    narrowed = catalog_for(tmp_path, "narrowed")
    env = {"SOURCE_DATE_EPOCH": "1700000000"}
    args = ["replay", str(flights / "a.mcap"), "-c", str(narrowed), "-f", "junit"]
    # The recorded commands, replayed: their recorded lines, in the recorded mission.
    code, out, _ = _cli(*args, env=env)
    assert code == 0
    (case,) = _suite(out).findall("testcase")
    assert case.find("failure") is not None
    assert (case.get("file"), case.get("line")) == (APPENDIX_C.name, str(FAR_POINT))
    # Your copy of the mission, moved down two lines: the lines of your copy.
    mine = tmp_path / "mine.py"
    mine.write_text("# mine\n\n" + APPENDIX_C.read_text(encoding="utf-8"), encoding="utf-8")
    code, out, _ = _cli(*args, "-m", str(mine), "-o", str(tmp_path / "r.mcap"), env=env)
    (case,) = _suite(out).findall("testcase")
    assert (case.get("file"), case.get("line")) == (str(mine), str(FAR_POINT + 2))
    # The same line in a diff of the recording and that replay, and in JSON.
    # (a recording names its mission by its file name).
    code, out, _ = _cli("diff", str(flights / "a.mcap"), str(tmp_path / "r.mcap"), "-f", "junit")
    (case,) = _suite(out).findall("testcase")
    assert (case.get("file"), case.get("line")) == (mine.name, str(FAR_POINT + 2))
    code, out, _ = _cli(*args[:-2], "-f", "json")
    (first, *_) = json.loads(out)["recordings"][0]["differences"]
    assert first["line"] == FAR_POINT
    # Shards merged give the report of the whole run, lines included.
    shard = tmp_path / "shard.json"
    code, out, _ = _cli(*args[:-2], "--shard", "1/1", "-f", "json")
    shard.write_text(out, encoding="utf-8")
    merged = _cli("report", "merge", str(shard), "-f", "junit", env=env)[1]
    assert merged == _cli(*args, env=env)[1]


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
    assert xml.splitlines()[1].startswith('<testsuites name="aeroexec replay" tests="1"')
