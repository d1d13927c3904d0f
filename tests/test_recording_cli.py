"""`aeroexec info` and `aeroexec recover`: output, foreign files, bad input, exit codes."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
from mcap.reader import make_reader
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.mission import APPENDIX_C, SessionConfig, simulate

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "recording"
TALKER = FIXTURES / "mcap_ros2_talker_zstd.mcap"
MSGTYPES = FIXTURES / "mcap_ros2_94_msgtypes_rosbags_rs.mcap"


@pytest.fixture(scope="module")
def session_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("rec") / "appendix_c.mcap"
    simulate(SessionConfig(mission=APPENDIX_C, record=path))
    return path


def _invoke(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, list(args))
    return result.exit_code, result.stdout, result.stderr


def _mcap_counts(path: Path) -> dict[str, int]:
    counts: dict[str, int] = {}
    with open(path, "rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        if summary is not None:
            counts = {channel.topic: 0 for channel in summary.channels.values()}
        for _, channel, _ in reader.iter_messages(log_time_order=False):
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
    return counts


# -- info ---------------------------------------------------------------------------------------
def test_info_json_counts_match_mcap(session_file: Path) -> None:
    code, out, err = _invoke("info", str(session_file), "--format", "json")
    assert code == 0 and err == ""
    report = json.loads(out)
    counts = _mcap_counts(session_file)
    assert report["channels"] == counts
    assert report["messages"] == sum(counts.values())
    assert report["complete"] is True and report["problem"] is None
    assert report["duration_s"] == pytest.approx(18.6)
    assert report["metadata"]["aeroexec"]["mission"] == "appendix_c.py"
    assert [a["name"] for a in report["attachments"]][:2] == ["catalog.yaml", "mission.py"]


def test_info_lists_behaviors_with_outcomes(session_file: Path) -> None:
    code, out, _ = _invoke("info", str(session_file), "--format", "json")
    assert code == 0
    runs = json.loads(out)["behaviors"]
    assert [(r["behavior"], r["outcome"]) for r in runs] == [
        ("TAKE_OFF", "GOAL_ACHIEVED"),
        ("PAY_ATTENTION_TO_VISUAL_MARKERS", "INTERRUPTED"),
        ("GO_TO_POINT", "GOAL_ACHIEVED"),
        ("GO_TO_POINT", "GOAL_ACHIEVED"),
        ("ROTATE", "GOAL_ACHIEVED"),
        ("GO_TO_POINT", "GOAL_ACHIEVED"),
        ("LAND", "GOAL_ACHIEVED"),
    ]
    assert [r["uid"] for r in runs] == [1, 2, 3, 4, 5, 6, 7]
    assert runs[1]["ended_s"] == pytest.approx(15.6) and runs[1]["detail"] == "inhibited"
    assert all(r["accepted"] for r in runs)


def test_info_text(session_file: Path) -> None:
    code, out, _ = _invoke("info", str(session_file))
    assert code == 0
    assert "complete:    yes" in out
    assert "duration:    18.600 s" in out
    assert "ROTATE #5: GOAL_ACHIEVED at 10.300 s" in out
    rows = [line.split() for line in out.splitlines() if line.startswith("  ")]
    assert ["7", "/drone1/activate_behavior", "json", "aeroexec.ServiceCall"] in rows


def test_info_reports_rejected_activations(tmp_path: Path) -> None:
    mission = tmp_path / "m.py"
    mission.write_text(
        "import executive_engine_api as api\n"
        "def runMission():\n"
        "    api.activateBehavior('GO_TO_POINT', coordinates=[500, 0, 1])\n"
        "    api.executeBehavior('TAKE_OFF')\n"
    )
    out_file = tmp_path / "r.mcap"
    simulate(SessionConfig(mission=mission, record=out_file))
    code, out, _ = _invoke("info", str(out_file), "--format", "json")
    runs = json.loads(out)["behaviors"]
    assert code == 0
    assert runs[0]["behavior"] == "GO_TO_POINT" and runs[0]["accepted"] is False
    assert runs[0]["error"] and runs[0]["outcome"] is None
    assert runs[1]["behavior"] == "TAKE_OFF" and runs[1]["outcome"] == "GOAL_ACHIEVED"


@pytest.mark.parametrize("fixture", [TALKER, MSGTYPES], ids=["talker", "94msgtypes"])
def test_info_on_foreign_mcap_counts_match_mcap(fixture: Path) -> None:
    code, out, err = _invoke("info", str(fixture), "--format", "json")
    assert code == 0 and err == ""
    report = json.loads(out)
    assert report["profile"] == "ros2"
    assert report["channels"] == _mcap_counts(fixture)
    assert report["messages"] == sum(_mcap_counts(fixture).values())
    assert report["behaviors"] == []
    # a ROS 2 MCAP is read as a ROS 2 bag (its topics by their original names)
    assert any("a ROS 2 bag" in note for note in report["notes"])
    code, text, _ = _invoke("info", str(fixture))
    assert code == 0 and "profile:     ros2" in text


def test_info_on_truncated_file_is_a_partial_read(session_file: Path, tmp_path: Path) -> None:
    data = session_file.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) * 2 // 3])
    code, out, err = _invoke("info", str(cut), "--format", "json")
    assert code == 0
    report = json.loads(out)
    assert report["complete"] is False and "byte" in report["problem"]
    assert 0 < report["messages"] < sum(_mcap_counts(session_file).values())
    assert err.startswith(f"{cut}: warning: incomplete recording") and err.count("\n") == 1
    code, out, _ = _invoke("info", str(cut))
    assert "complete:    NO" in out and "aeroexec recover" in out


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"", "empty file"),
        (os.urandom(4096).replace(b"\x89", b"\x00"), "not an MCAP file"),
        (b"\x89MCAP0\r\n\x01\x20\x00", "ends before the MCAP header"),
    ],
    ids=["empty", "random", "truncated-header"],
)
def test_info_unreadable_exit_2_one_line(tmp_path: Path, content: bytes, message: str) -> None:
    path = tmp_path / "bad.mcap"
    path.write_bytes(content)
    code, out, err = _invoke("info", str(path))
    assert code == 2 and out == ""
    assert err == f"{path}: error: {err.split(': error: ', 1)[1]}"
    assert message in err and err.count("\n") == 1 and "Traceback" not in err


def test_info_missing_file_and_directory(tmp_path: Path) -> None:
    code, _, err = _invoke("info", str(tmp_path / "nope.mcap"))
    assert code == 2 and err == f"{tmp_path / 'nope.mcap'}: error: no such file\n"
    code, _, err = _invoke("info", str(tmp_path))
    assert code == 2 and err == f"{tmp_path}: error: is a directory, not a recording\n"


# -- recover ------------------------------------------------------------------------------------
def test_recover_truncated_file_gives_a_complete_file(session_file: Path, tmp_path: Path) -> None:
    data = session_file.read_bytes()
    broken, fixed = tmp_path / "broken.mcap", tmp_path / "fixed.mcap"
    broken.write_bytes(data[: len(data) // 2])
    code, out, _ = _invoke("recover", str(broken), "-o", str(fixed), "--format", "json")
    assert code == 0
    report = json.loads(out)
    assert report["source_complete"] is False and report["messages"] > 0
    with open(fixed, "rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        recovered = [(c.topic, m.log_time, m.data) for _, c, m in reader.iter_messages()]
        attachments = [a.name for a in reader.iter_attachments()]
        metadata = [m.name for m in reader.iter_metadata()]
    assert summary is not None and summary.statistics is not None
    assert summary.statistics.message_count == report["messages"] == len(recovered)
    with open(session_file, "rb") as stream:
        original = [
            (c.topic, m.log_time, m.data)
            for _, c, m in make_reader(stream).iter_messages(log_time_order=False)
        ]
    assert recovered == original[: len(recovered)]
    assert attachments == ["catalog.yaml", "mission.py", "world.yaml"]
    # The session's own metadata, then what recover says about the copy: cut short.
    assert metadata == ["aeroexec", "behaviors", "aeroexec_recover"]
    with open(fixed, "rb") as stream:
        said = {m.name: m.metadata for m in make_reader(stream).iter_metadata()}
    assert said["aeroexec_recover"]["cut"].startswith("chunk record at byte")
    assert said["aeroexec_recover"]["messages_copied"] == str(len(recovered))
    code, out, _ = _invoke("info", str(fixed), "--format", "json")
    assert json.loads(out)["complete"] is True


def test_recover_complete_file_keeps_everything(session_file: Path, tmp_path: Path) -> None:
    fixed = tmp_path / "copy.mcap"
    code, out, _ = _invoke("recover", str(session_file), "-o", str(fixed))
    assert code == 0 and "source was complete" in out
    assert _mcap_counts(fixed) == _mcap_counts(session_file)


def test_recover_foreign_file_keeps_schemas_and_counts(tmp_path: Path) -> None:
    fixed = tmp_path / "talker.mcap"
    code, _, _ = _invoke("recover", str(TALKER), "-o", str(fixed))
    assert code == 0
    assert _mcap_counts(fixed) == _mcap_counts(TALKER)
    with open(fixed, "rb") as stream:
        reader = make_reader(stream)
        assert reader.get_header().profile == "ros2"
        schemas = {s.name for s, _, _ in reader.iter_messages()}
    assert schemas == {"std_msgs/msg/String", "rcl_interfaces/msg/Log"}


def test_recover_bad_inputs_exit_2_and_write_nothing(tmp_path: Path) -> None:
    junk, fixed = tmp_path / "junk.mcap", tmp_path / "fixed.mcap"
    junk.write_bytes(b"definitely not mcap" * 10)
    code, _, err = _invoke("recover", str(junk), "-o", str(fixed))
    assert code == 2 and err == f"{junk}: error: not an MCAP file (bad magic bytes)\n"
    assert not fixed.exists()
    code, _, err = _invoke("recover", str(tmp_path / "absent.mcap"), "-o", str(fixed))
    assert code == 2 and "no such file" in err and not fixed.exists()


def test_recover_refuses_to_overwrite_its_source(session_file: Path, tmp_path: Path) -> None:
    copy = tmp_path / "same.mcap"
    copy.write_bytes(session_file.read_bytes())
    code, _, err = _invoke("recover", str(copy), "-o", str(copy))
    assert code == 2 and "different file" in err
    assert copy.read_bytes() == session_file.read_bytes()


@pytest.mark.parametrize("command", ["info", "recover"])
def test_help_has_an_example(command: str) -> None:
    code, out, _ = _invoke(command, "--help")
    assert code == 0
    assert "Example" in out and f"aeroexec {command} " in out
