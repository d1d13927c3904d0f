"""`aeroexec replay`: exit codes, formats, batches, parallel jobs, bad input."""

from __future__ import annotations

import json
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from test_replay_support import (
    APPENDIX_C,
    DEFAULT_CATALOG_FILE,
    REPO,
    SURVEY,
    WATCH,
    catalog_for,
    record,
)
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.recording import Recorder

runner = CliRunner()


def cli(*args: str) -> tuple[int, str, str]:
    result = runner.invoke(app, list(args))
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(
        result.exception
    )
    return result.exit_code, result.stdout, result.stderr


@pytest.fixture(scope="module")
def work(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("replay_cli")


@pytest.fixture(scope="module")
def flights(work: Path) -> Path:
    """A directory of three recordings (sorted: appendix_c, survey, watch)."""
    directory = work / "flights"
    directory.mkdir()
    record(directory / "appendix_c.mcap", APPENDIX_C)
    record(directory / "survey.mcap", SURVEY)
    record(directory / "watch.mcap", WATCH)
    (directory / "notes.txt").write_text("not a recording")
    return directory


@pytest.fixture(scope="module")
def narrowed(work: Path) -> Path:
    return catalog_for(work, "narrowed")


def one_error_line(stderr: str) -> str:
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    assert "Traceback" not in stderr
    return lines[0]


# -- results and exit codes ------------------------------------------------------------------
def test_check_passes_on_unchanged_recordings(flights: Path) -> None:
    code, out, err = cli("replay", str(flights), "--check", "--trust-recording")
    assert code == 0
    lines = out.strip().splitlines()
    assert lines == [
        f"{flights / 'appendix_c.mcap'}: closed-loop replay with its recorded default.yaml: "
        "no differences (9 commands compared)",
        f"{flights / 'survey.mcap'}: closed-loop replay with its recorded default.yaml: "
        "no differences (7 commands compared)",
        f"{flights / 'watch.mcap'}: closed-loop replay with its recorded default.yaml: "
        "no differences (10 commands compared)",
        "3 recordings: 0 with differences, 3 without, 0 unreadable",
    ]
    assert err == ""  # no progress bar when stderr is not a terminal


def test_check_fails_on_differences(flights: Path, narrowed: Path) -> None:
    code, out, _ = cli("replay", str(flights), "--catalog", str(narrowed), "--check")
    assert code == 1
    assert (
        "  #4 GO_TO_POINT coordinates=[3, 5.5, 1.3] now rejected: GO_TO_POINT: "
        "COORDINATES needs 3 numbers "
        "in [-2, 2], got [3, 5.5, 1.3] (3 is outside)\n" in out
    )
    assert out.strip().endswith("3 recordings: 2 with differences, 1 without, 0 unreadable")


def test_without_check_differences_do_not_fail(flights: Path, narrowed: Path) -> None:
    code, out, _ = cli(
        "replay", str(flights / "survey.mcap"), "--catalog", str(narrowed), "--trust-recording"
    )
    assert code == 0
    assert "3 differences (6 commands compared)" in out


def test_junit_has_one_testcase_per_recording(flights: Path, narrowed: Path) -> None:
    code, out, _ = cli(
        "replay",
        str(flights),
        "--catalog",
        str(narrowed),
        "--check",
        "--format",
        "junit",
        "--trust-recording",
    )
    assert code == 1
    root = ET.fromstring(out)
    assert root.tag == "testsuites"
    (suite,) = root.findall("testsuite")
    assert (suite.get("tests"), suite.get("failures"), suite.get("errors")) == ("3", "2", "0")
    cases = suite.findall("testcase")
    assert [c.get("name") for c in cases] == [
        str(flights / n) for n in ("appendix_c.mcap", "survey.mcap", "watch.mcap")
    ]
    appendix, survey, watch = cases
    failure = appendix.find("failure")
    assert failure is not None
    assert failure.get("message") == "2 differences"
    assert "#4 GO_TO_POINT coordinates=[3, 5.5, 1.3] now rejected" in (failure.text or "")
    # The recorded script ran (--trust-recording): the report points at its line.
    far = next(
        n
        for n, text in enumerate(APPENDIX_C.read_text(encoding="utf-8").splitlines(), 1)
        if "coordinates=[3, 5.5, 1.3]" in text
    )
    assert (appendix.get("file"), appendix.get("line")) == (APPENDIX_C.name, str(far))
    survey_failure = survey.find("failure")
    assert survey_failure is not None
    assert "only in the recording: the mission took another path" in (survey_failure.text or "")
    assert watch.find("failure") is None and watch.find("error") is None


def test_json_is_one_object_with_equal_and_differences(flights: Path, narrowed: Path) -> None:
    code, out, _ = cli(
        "replay", str(flights / "appendix_c.mcap"), "--catalog", str(narrowed), "--format", "json"
    )
    assert code == 0
    document = json.loads(out)
    assert document["equal"] is False
    assert [(d["command"], d["kind"]) for d in document["differences"]] == [
        (4, "accepted"),
        (6, "end_time"),
    ]
    first = document["differences"][0]
    assert first["recording"] == str(flights / "appendix_c.mcap")
    assert first["message"].startswith("#4 GO_TO_POINT coordinates=[3, 5.5, 1.3] now rejected: ")
    assert document["recordings"][0]["mode"] == "closed"


def test_tolerance_option(flights: Path, narrowed: Path) -> None:
    """The way home drifts 5.2 s: reported at 0.5 s, not at 6 s."""
    path = str(flights / "appendix_c.mcap")
    _, loose, _ = cli("replay", path, "-c", str(narrowed), "--format", "json", "--tolerance", "6")
    assert [d["kind"] for d in json.loads(loose)["differences"]] == ["accepted"]


def test_parallel_jobs_give_the_same_report_in_input_order(flights: Path, narrowed: Path) -> None:
    args = ["replay", str(flights), "--catalog", str(narrowed), "--format", "json"]
    _, serial, _ = cli(*args)
    _, parallel, _ = cli(*args, "--jobs", "3")
    assert parallel == serial


def test_mode_option_forces_open_loop(flights: Path, narrowed: Path) -> None:
    code, out, _ = cli(
        "replay", str(flights / "appendix_c.mcap"), "-c", str(narrowed), "--mode", "open"
    )
    assert code == 0
    assert "open-loop replay" in out
    assert "1 difference (9 commands compared)" in out


def test_globs_and_out_dir(flights: Path, work: Path) -> None:
    out_dir = work / "replays"
    code, out, _ = cli(
        "replay",
        str(flights / "[as]*.mcap"),
        "--output-dir",
        str(out_dir),
        "--check",
        "--trust-recording",
    )
    assert code == 0
    assert "2 recordings: 0 with differences, 2 without, 0 unreadable" in out
    assert sorted(p.name for p in out_dir.iterdir()) == ["appendix_c.mcap", "survey.mcap"]
    for name in ("appendix_c.mcap", "survey.mcap"):
        assert (out_dir / name).read_bytes() == (flights / name).read_bytes()


def test_output_file_is_byte_identical(flights: Path, work: Path) -> None:
    out = work / "one.mcap"
    code, text, _ = cli("replay", str(flights / "watch.mcap"), "-o", str(out), "--trust-recording")
    assert code == 0
    assert f"replay written to {out}" in text
    assert out.read_bytes() == (flights / "watch.mcap").read_bytes()


def test_help_has_an_example() -> None:
    code, out, _ = cli("replay", "--help")
    assert code == 0
    assert "aeroexec replay flight.mcap --catalog" in out
    assert "Exit codes" in out


# -- bad input: exit 2, one line, no traceback ---------------------------------------------
def test_missing_file(work: Path) -> None:
    code, out, err = cli("replay", str(work / "nope.mcap"))
    assert code == 2
    assert one_error_line(err) == f"{work / 'nope.mcap'}: error: no such file"
    assert out == ""


def test_not_mcap(work: Path) -> None:
    path = work / "text.mcap"
    path.write_text("hello, not a recording\n")
    code, _, err = cli("replay", str(path), "--check")
    assert code == 2
    assert one_error_line(err) == f"{path}: error: not an MCAP file (bad magic bytes)"


def test_cut_inside_the_header(flights: Path, work: Path) -> None:
    path = work / "header.mcap"
    path.write_bytes((flights / "watch.mcap").read_bytes()[:20])
    code, _, err = cli("replay", str(path))
    assert code == 2
    assert "ends inside the MCAP header" in one_error_line(err)


def test_truncated_recording_is_compared_up_to_the_cut(flights: Path, work: Path) -> None:
    """A recording cut short (a crash) is replayed; both runs are compared up to where
    the file stops, and the report says so."""
    data = (flights / "appendix_c.mcap").read_bytes()
    path = work / "cut.mcap"
    path.write_bytes(data[: len(data) // 3])
    code, out, err = cli("replay", str(path), "--check")
    assert code == 0, out
    assert err == ""
    assert "no differences" in out
    assert "note: incomplete recording (" in out
    assert "compared the first" in out


def test_mcap_without_mission_commands(work: Path) -> None:
    path = work / "quiet.mcap"
    with Recorder(path, metadata={"clock": "sim"}) as recorder:
        recorder.write_topic("log", {"message": "nothing happened"}, 0)
    code, _, err = cli("replay", str(path), "--check")
    assert code == 2
    assert one_error_line(err).endswith(
        "no mission commands in this recording (mission/command is empty): nothing to replay"
    )


def test_foreign_mcap() -> None:
    """A ROS 2 MCAP is a bag (imported first, Aerostack2 mapping): the talker has no
    behavior topics, so nothing to replay."""
    path = REPO / "tests" / "fixtures" / "recording" / "mcap_ros2_talker_zstd.mcap"
    code, _, err = cli("replay", str(path))
    assert code == 2
    assert one_error_line(err).startswith(
        f"{path}: error: no behavior commands to replay: the bag has none of the behavior "
        "topics the Aerostack2 mapping knows"
    )


def test_a_bad_recording_in_a_batch(flights: Path, work: Path) -> None:
    batch = work / "batch"
    batch.mkdir()
    shutil.copy(flights / "watch.mcap", batch / "a.mcap")
    (batch / "b.mcap").write_bytes(b"\x89MCAP0\r\nbroken")
    code, out, err = cli("replay", str(batch), "--check", "--format", "junit", "--jobs", "2")
    assert code == 2
    assert "b.mcap: error: " in one_error_line(err)
    (suite,) = ET.fromstring(out).findall("testsuite")
    assert (suite.get("tests"), suite.get("failures"), suite.get("errors")) == ("2", "0", "1")
    good, bad = suite.findall("testcase")
    assert good.find("error") is None
    assert bad.find("error") is not None


def test_empty_directory_and_unmatched_glob(work: Path) -> None:
    empty = work / "empty"
    empty.mkdir()
    code, _, err = cli("replay", str(empty))
    assert code == 2
    assert one_error_line(err) == (
        f"{empty}: error: no *.mcap recordings in this directory (nor ROS bags: *.bag, "
        "*.db3, rosbag2 directories)"
    )
    code, _, err = cli("replay", str(work / "zz*.mcap"))
    assert code == 2
    assert one_error_line(err).endswith("error: no recordings match this pattern")


def test_bad_catalog(flights: Path, work: Path) -> None:
    broken = work / "broken.yaml"
    broken.write_text("behavior_descriptors: [\n")
    code, _, err = cli("replay", str(flights / "watch.mcap"), "--catalog", str(broken))
    assert code == 2
    assert one_error_line(err).startswith(str(broken))


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["-o", "x.mcap", "--output-dir", "d"], "not both"),
        (["--tolerance", "-1"], "non-negative"),
    ],
)
def test_bad_options(flights: Path, extra: list[str], needle: str) -> None:
    code, _, err = cli("replay", str(flights / "watch.mcap"), *extra)
    assert code == 2
    assert needle in one_error_line(err)


def test_output_needs_one_recording_and_never_overwrites_its_input(
    flights: Path, work: Path
) -> None:
    code, _, err = cli("replay", str(flights), "-o", str(work / "x.mcap"))
    assert code == 2
    assert "takes one recording, got 3" in one_error_line(err)
    target = work / "self.mcap"
    shutil.copy(flights / "watch.mcap", target)
    before = target.read_bytes()
    code, _, err = cli("replay", str(target), "-o", str(target))
    assert code == 2
    assert "would overwrite a recording being replayed" in one_error_line(err)
    assert target.read_bytes() == before


def test_a_directory_with_a_ros1_bag(flights: Path, work: Path) -> None:
    """Bags in a directory are replayed too (open loop, through aeroexec.bags' import),
    and their replays are written as .mcap files."""
    from test_bags_support import short_mission

    mixed = work / "mixed"
    mixed.mkdir()
    short_mission().write(mixed / "b_flight.bag")
    shutil.copy(flights / "watch.mcap", mixed / "a_watch.mcap")
    out_dir = work / "mixed-replays"
    code, out, err = cli(
        "replay", str(mixed), "--catalog", str(DEFAULT_CATALOG_FILE), "--check", "--format", "json",
        "--output-dir", str(out_dir),
    )  # fmt: skip
    assert code == 0, err
    recordings = json.loads(out)["recordings"]
    assert [(r["recording"], r["mode"], r["equal"]) for r in recordings] == [
        (str(mixed / "a_watch.mcap"), "closed", True),
        (str(mixed / "b_flight.bag"), "open", True),
    ]
    assert sorted(p.name for p in out_dir.iterdir()) == ["a_watch.mcap", "b_flight.mcap"]


def test_progress_bar_only_on_a_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    import sys

    from aeroexec.cli.replay_cmd import _progress

    monkeypatch.setattr(sys.stderr, "isatty", lambda: False)
    assert _progress(3) is None
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    bar = _progress(3)
    assert bar is not None and type(bar).__module__ == "rich.progress"
    assert _progress(0) is None


def test_diff_help_has_an_example() -> None:
    code, out, _ = cli("diff", "--help")
    assert code == 0
    assert "aeroexec diff flight.mcap replayed.mcap" in out
    assert "Exit codes" in out
