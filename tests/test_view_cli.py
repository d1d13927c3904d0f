"""`aeroexec view` on the command line: where the file goes, when the viewer opens,
and one clear line with exit code 2 for anything that is not a readable aeroexec
recording."""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import Any

import pytest
from as2_support import write_flight
from rerun.chunk import RrdReader
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.mission import APPENDIX_C, SessionConfig, simulate

FIXTURES = Path(__file__).resolve().parent / "fixtures"
ROS2_BAG = FIXTURES / "view" / "mcap_ros2_talker_zstd.mcap"


@pytest.fixture(scope="module")
def session_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("view_cli") / "flight.mcap"
    simulate(SessionConfig(mission=APPENDIX_C, record=path))
    return path


@pytest.fixture()
def flight(session_file: Path, tmp_path: Path) -> Path:
    """A private copy, so default outputs land in this test's directory."""
    copy = tmp_path / "flight.mcap"
    shutil.copyfile(session_file, copy)
    return copy


@pytest.fixture()
def headless(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr("sys.platform", "linux")


@pytest.fixture()
def launches(monkeypatch: pytest.MonkeyPatch) -> list[tuple[Path, bool]]:
    """Record viewer launches instead of starting one, as if it could run."""
    calls: list[tuple[Path, bool]] = []

    def fake_open(rrd: Path) -> None:
        calls.append((rrd, False))

    monkeypatch.setattr("aeroexec.viz.viewer.open_viewer", fake_open)
    monkeypatch.setattr("aeroexec.viz.viewer.cannot_spawn", lambda web=False: None)
    return calls


@pytest.fixture()
def served(monkeypatch: pytest.MonkeyPatch) -> list[tuple[Path, str, int]]:
    """Record web viewer launches (file, bind address, port) instead of serving."""
    calls: list[tuple[Path, str, int]] = []

    def fake_serve(rrd: Path, *, bind: str, port: int, on_ready: Any) -> int:
        calls.append((rrd, bind, port))
        on_ready(f"http://{bind}:{port}", 1)
        return 0

    monkeypatch.setattr("aeroexec.viz.viewer.serve_web", fake_serve)
    monkeypatch.setattr("aeroexec.viz.viewer.cannot_spawn", lambda web=False: None)
    return calls


def _invoke(*args: str | Path) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, [str(a) for a in args])
    return result.exit_code, result.stdout, result.stderr


def _entities(rrd: Path) -> set[str]:
    return {chunk.entity_path for chunk in RrdReader(rrd).stream()}


# -- where the file goes, and the viewer ------------------------------------------------
def test_default_writes_next_to_the_input_and_says_why_no_viewer(
    flight: Path, headless: None
) -> None:
    code, out, err = _invoke("view", flight)
    target = flight.with_suffix(".rrd")
    assert code == 0, err
    assert target.is_file()
    assert f"wrote {target}" in out
    assert "viewer not started: no display" in err
    assert f"rerun {target}" in err  # how to open it later
    assert "/trajectory" in _entities(target)


def test_save_writes_there_and_does_not_spawn(
    flight: Path, tmp_path: Path, launches: list[tuple[Path, bool]]
) -> None:
    target = tmp_path / "out" / "x.rrd"
    target.parent.mkdir()
    code, _, err = _invoke("view", flight, "--output", target)
    assert code == 0, err
    assert target.is_file() and not flight.with_suffix(".rrd").exists()
    assert launches == []
    assert "viewer" not in err


def test_viewer_opens_on_the_written_file_when_it_can_run(
    flight: Path, launches: list[tuple[Path, bool]]
) -> None:
    code, out, err = _invoke("view", flight)
    assert code == 0, err
    assert launches == [(flight.with_suffix(".rrd"), False)]
    assert "opening the Rerun viewer" in out


def test_save_with_spawn_opens_the_saved_file(
    flight: Path, tmp_path: Path, launches: list[tuple[Path, bool]]
) -> None:
    target = tmp_path / "s.rrd"
    assert _invoke("view", flight, "--output", target, "--spawn")[0] == 0
    assert launches == [(target, False)]


def test_no_spawn_writes_the_file_only(flight: Path, launches: list[tuple[Path, bool]]) -> None:
    code, _, err = _invoke("view", flight, "--no-spawn")
    assert code == 0, err
    assert flight.with_suffix(".rrd").is_file()
    assert launches == []


def test_web_serves_on_this_machine_only_by_default(
    flight: Path, launches: list[tuple[Path, bool]], served: list[tuple[Path, str, int]]
) -> None:
    code, out, _ = _invoke("view", flight, "--web", "--no-spawn")
    assert code == 0
    assert launches == []
    assert served == [(flight.with_suffix(".rrd"), "127.0.0.1", 9090)]
    assert "serving the web viewer at http://127.0.0.1:9090 (Ctrl-C to stop)" in out


def test_web_port_and_allow_remote(flight: Path, served: list[tuple[Path, str, int]]) -> None:
    code, _, err = _invoke("view", flight, "--web", "--port", "9191", "--allow-remote")
    assert code == 0, err
    assert served == [(flight.with_suffix(".rrd"), "0.0.0.0", 9191)]


@pytest.mark.parametrize("args", [["--port", "9191"], ["--allow-remote"]])
def test_web_options_without_web_are_refused(flight: Path, args: list[str]) -> None:
    code, out, err = _invoke("view", flight, *args)
    assert code == 2 and out == ""
    assert (
        err == "aeroexec view: error: --port and --allow-remote are for the web viewer: add --web\n"
    )
    assert not flight.with_suffix(".rrd").exists()


def test_a_bag_is_imported_and_viewed(tmp_path: Path, headless: None) -> None:
    bag = tmp_path / "flight.bag"
    shutil.copyfile(FIXTURES / "bags" / "aerostack_2017_first_view_ros1.bag", bag)
    code, out, err = _invoke("view", bag, "--no-spawn")
    assert code == 0, err
    target = tmp_path / "flight.rrd"
    assert f"wrote {target}" in out
    assert f"{bag}: 282 messages, 123 vehicle states" in out
    assert {"/trajectory", "/vehicle", "/processes/droneCommand"} <= _entities(target)
    assert "not decoded" not in err  # the bag's own ROS 1 channels are not news
    assert set(tmp_path.iterdir()) == {bag, target}  # nothing else next to the bag


def test_a_bag_without_mapped_topics_is_refused(tmp_path: Path) -> None:
    bag = tmp_path / "turtle.bag"
    shutil.copyfile(FIXTURES / "bags" / "ros1_turtlesim_example_lz4.bag", bag)
    code, out, err = _invoke("view", bag, "--no-spawn")
    assert code == 2 and out == ""
    assert err.startswith(f"{bag}: error: nothing to show: the bag has none of the topics")
    assert err.count("\n") == 1
    assert not (tmp_path / "turtle.rrd").exists()


def test_two_recordings_default_name_and_both_roots(
    flight: Path, tmp_path: Path, headless: None
) -> None:
    other = tmp_path / "replay.mcap"
    shutil.copyfile(flight, other)
    code, out, err = _invoke("view", flight, other, "--no-spawn")
    assert code == 0, err
    target = tmp_path / "flight_vs_replay.rrd"
    assert target.is_file()
    entities = _entities(target)
    assert {"/base/events", "/new/events", "/base/trajectory", "/new/trajectory"} <= entities
    assert "under /base" in out and "under /new" in out


def test_incomplete_recording_is_shown_with_a_warning(flight: Path, tmp_path: Path) -> None:
    data = flight.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) * 2 // 3])
    code, _, err = _invoke("view", cut, "--no-spawn")
    assert code == 0, err
    assert "warning: incomplete recording" in err
    assert (tmp_path / "cut.rrd").is_file()


def test_help_has_an_example() -> None:
    code, out, _ = _invoke("view", "--help")
    assert code == 0
    assert "aeroexec view flight.mcap" in out
    assert "--output" in out and "--web" in out


# -- inputs that are not readable aeroexec recordings -----------------------------------
def _assert_one_line_error(code: int, out: str, err: str, *needles: str) -> None:
    assert code == 2
    assert "Traceback" not in out + err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    for needle in needles:
        assert needle in lines[0]


def test_random_bytes(tmp_path: Path) -> None:
    bad = tmp_path / "noise.mcap"
    bad.write_bytes(os.urandom(4096))
    code, out, err = _invoke("view", bad, "--no-spawn")
    _assert_one_line_error(code, out, err, str(bad), "not an MCAP file")
    assert not bad.with_suffix(".rrd").exists()


def test_truncated_to_the_header(flight: Path, tmp_path: Path) -> None:
    cut = tmp_path / "head.mcap"
    cut.write_bytes(flight.read_bytes()[:100])
    code, out, err = _invoke("view", cut, "--no-spawn")
    _assert_one_line_error(code, out, err, str(cut), "no messages could be read")
    assert not cut.with_suffix(".rrd").exists()


def test_truncated_inside_the_magic(flight: Path, tmp_path: Path) -> None:
    cut = tmp_path / "magic.mcap"
    cut.write_bytes(flight.read_bytes()[:5])
    code, out, err = _invoke("view", cut, "--no-spawn")
    _assert_one_line_error(code, out, err, str(cut))


def test_ros2_mcap_without_mapped_topics_is_refused(tmp_path: Path) -> None:
    """A ROS 2 MCAP is a bag: imported first (Aerostack2 mapping); the talker has none
    of its topics."""
    assert ROS2_BAG.is_file()
    code, out, err = _invoke("view", ROS2_BAG, "--output", tmp_path / "x.rrd")
    _assert_one_line_error(code, out, err, "nothing to show: the bag has none of the topics")
    assert not (tmp_path / "x.rrd").exists()


def test_foreign_second_recording_writes_nothing(flight: Path, tmp_path: Path) -> None:
    code, out, err = _invoke("view", flight, ROS2_BAG, "--no-spawn")
    _assert_one_line_error(code, out, err, "nothing to show")
    assert list(tmp_path.glob("*.rrd")) == []


def test_an_aerostack2_bag_directory_is_imported_and_viewed(tmp_path: Path, headless: None) -> None:
    bag = write_flight(tmp_path / "rosbag2_flight", "sqlite3")
    code, out, err = _invoke("view", bag, "--no-spawn")
    assert code == 0, err
    target = tmp_path / "rosbag2_flight.rrd"
    assert f"wrote {target}" in out
    assert f"{bag}: " in out and "5 behavior events" in out and "4 behaviors" in out
    entities = _entities(target)
    assert {"/trajectory", "/vehicle"} <= entities
    assert any("TakeoffBehavior" in e for e in entities)
    assert set(tmp_path.iterdir()) == {bag, target}


def test_missing_file(tmp_path: Path) -> None:
    code, out, err = _invoke("view", tmp_path / "nope.mcap")
    _assert_one_line_error(code, out, err, "no such file")


def test_unwritable_output(flight: Path, tmp_path: Path) -> None:
    code, out, err = _invoke("view", flight, "--output", tmp_path / "no" / "dir" / "x.rrd")
    _assert_one_line_error(code, out, err, "cannot write")
    code, out, err = _invoke("view", flight, "--output", tmp_path)
    _assert_one_line_error(code, out, err, "is a directory")


def test_rerun_disabled_in_the_environment_is_an_error_not_an_empty_file(
    flight: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("RERUN", "off")
    code, out, err = _invoke("view", flight, "--no-spawn")
    _assert_one_line_error(code, out, err, "RERUN=off")
    assert not flight.with_suffix(".rrd").exists()
