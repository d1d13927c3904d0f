"""Recordings that lie: damage in the middle is found, stepped over and reported.

A zero-filled chunk, a flipped byte (CRC mismatch), a damaged attachment, a file cut
short: `info`, `recover`, `replay` and `diff` each say what is missing where, never
`complete: yes` for a file that holds less than its own statistics promise, and never a
difference that only the damage made up.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mcap.reader import make_reader
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.errors import RecordingError
from aeroexec.mission.session import SessionConfig, simulate
from aeroexec.recording import open_recording, recover
from aeroexec.replay.collect import read_run
from aeroexec.replay.engine import diff_recordings

REPO = Path(__file__).resolve().parents[1]
MISSION = REPO / "missions" / "appendix_c.py"
runner = CliRunner()


def cli(*args: str) -> tuple[int, str, str]:
    result = runner.invoke(app, list(args))
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    return result.exit_code, result.stdout, result.stderr


@pytest.fixture(scope="module")
def flight(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("damage") / "flight.mcap"
    simulate(SessionConfig(mission=MISSION, record=path))
    return path


def chunks(path: Path) -> list[tuple[int, int, int, int]]:
    """(offset, length, first log time, last log time) of every chunk, from the summary."""
    with open(path, "rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    return [
        (c.chunk_start_offset, c.chunk_length, c.message_start_time, c.message_end_time)
        for c in summary.chunk_indexes
    ]


def messages(path: Path) -> list[tuple[str, int, bytes]]:
    return [(m.channel.topic, m.log_time_ns, m.data) for m in open_recording(path).messages()]


def damaged(flight: Path, tmp_path: Path, how: str, index: int = 3) -> tuple[Path, tuple[int, ...]]:
    offset, length, start, end = chunks(flight)[index]
    data = bytearray(flight.read_bytes())
    if how == "zero":
        data[offset : offset + length] = bytes(length)
    else:  # one flipped byte near the end of the chunk's compressed data: CRC mismatch
        data[offset + length - 5] ^= 0xFF
    path = tmp_path / f"{how}.mcap"
    path.write_bytes(bytes(data))
    return path, (offset, length, start, end)


@pytest.mark.parametrize("how", ["zero", "flip"])
def test_info_reports_the_damage_and_the_shortfall(flight: Path, tmp_path: Path, how: str) -> None:
    path, (offset, _length, start, end) = damaged(flight, tmp_path, how)
    whole, read = messages(flight), messages(path)
    lost = len(whole) - len(read)
    assert lost > 0
    # Everything else is read, in order: the damage is stepped over, not the end.
    head = next(i for i, (a, b) in enumerate(zip(read, whole, strict=False)) if a != b)
    assert read == whole[:head] + whole[head + lost :]
    code, out, err = cli("info", str(path), "--format", "json")
    assert code == 0
    report = json.loads(out)
    assert report["complete"] is False
    assert report["messages"] == len(read) and report["expected_messages"] == len(whole)
    [damage] = report["damages"]
    assert damage["offset"] == offset and damage["messages"] == lost
    assert (damage["start_ns"], damage["end_ns"]) == (start, end)
    assert damage["kind"] == ("zero-filled" if how == "zero" else "CRC mismatch")
    text = cli("info", str(path))[1]
    assert (
        f"complete:    NO: 1 damaged region, {len(read)} of the {len(whole)} messages read" in text
    )
    assert f"{lost} messages lost, log time {start / 1e9:.3f} .. {end / 1e9:.3f} s" in text
    assert err.startswith(f"{path}: warning: damaged recording: 1 damaged region: ")


def test_recover_says_in_the_copy_what_is_missing_where(flight: Path, tmp_path: Path) -> None:
    path, (offset, length, _start, _end) = damaged(flight, tmp_path, "zero")
    fixed = tmp_path / "fixed.mcap"
    code, out, _ = cli("recover", str(path), "-o", str(fixed))
    assert code == 0
    assert "source was complete" not in out
    whole, read = messages(flight), messages(path)
    assert f"source damaged: 1 region lost; {len(read)} of its {len(whole)} messages copied" in out
    assert f"{path}: not copied: bytes {offset}..{offset + length} zero-filled" in out
    said = open_recording(fixed).metadata["aeroexec_recover"]
    assert said["messages_copied"] == str(len(read))
    assert said["messages_expected"] == str(len(whole))
    assert said["damage_1"].startswith(f"bytes {offset}..{offset + length} zero-filled (")
    assert messages(fixed) == read
    info = json.loads(cli("info", str(fixed), "--format", "json")[1])
    assert any("recovered from a damaged" in note for note in info["notes"])


def test_replay_and_diff_compare_only_before_the_damage(flight: Path, tmp_path: Path) -> None:
    path, (_, _, start, _) = damaged(flight, tmp_path, "flip", index=2)
    code, out, _ = cli("replay", str(path), "--check", "--trust-recording")
    assert code == 0, out  # nothing lost is taken for a regression
    assert "note: damaged recording (1 damaged region: chunk at byte" in out
    assert f"compared the first {start / 1e9:.1f} s" in out
    code, out, _ = cli("diff", str(flight), str(path))
    assert code == 0, out
    assert f"{path} is damaged (1 damaged region" in out


def test_a_damaged_attachment_is_an_input_error_for_replay(flight: Path, tmp_path: Path) -> None:
    data = bytearray(flight.read_bytes())
    at = data.find(b"runMission")
    data[at] ^= 0x01  # one flipped bit in the stored mission script
    path = tmp_path / "attachment.mcap"
    path.write_bytes(bytes(data))
    code, _, err = cli("replay", str(path), "--check", "--trust-recording")
    assert code == 2
    assert re.fullmatch(
        rf"{re.escape(str(path))}: error: attachment 'mission.py' at byte \d+ is damaged "
        r"\(CRC mismatch\)",
        err.strip(),
    )
    report = json.loads(cli("info", str(path), "--format", "json")[1])
    assert report["complete"] is False
    assert [d["what"] for d in report["damages"]] == ["attachment 'mission.py'"]
    assert "mission.py" not in [a["name"] for a in report["attachments"]]


def test_a_zero_filled_tail_is_a_cut_not_garbage(flight: Path, tmp_path: Path) -> None:
    offset, _length, _, _ = chunks(flight)[5]
    data = flight.read_bytes()[:offset] + bytes(50_000)  # preallocated, never written
    path = tmp_path / "tail.mcap"
    path.write_bytes(data)
    recording = open_recording(path)
    assert not recording.complete and recording.end.damages == ()
    assert recording.problem == (
        f"bytes {offset}..{len(data)} are zero-filled to the end of the file (incomplete)"
    )


def test_diff_against_a_crashed_run_never_invents_a_final_state(
    flight: Path, tmp_path: Path
) -> None:
    """Cut anywhere after the first command, a run equals its base up to the cut."""
    data = flight.read_bytes()
    cut = tmp_path / "cut.mcap"
    noted = 0
    first = chunks(flight)[1][0]
    # Some 24 cuts, wherever the chunks fall (a simulated run's are 100 messages each).
    for size in range(first, len(data), (len(data) - first) // 24 | 1):
        cut.write_bytes(data[:size])
        for base, new in ((flight, cut), (cut, flight)):
            result = diff_recordings(base, new)
            assert result.equal, (size, [d.message for d in result.differences])
            if result.notes:  # (a cut inside the summary section loses no message)
                assert result.notes[0].startswith(f"{cut} is incomplete (")
                assert "compared both on their first" in result.notes[0]
                noted += 1
    assert noted >= 30


# -- fuzz ------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def small(tmp_path_factory: pytest.TempPathFactory) -> tuple[bytes, list[tuple[str, int, bytes]]]:
    """A short session (take off, land) recorded, with its messages."""
    folder = tmp_path_factory.mktemp("fuzz")
    script = folder / "short.py"
    script.write_text(
        "import executive_engine_api as api\n\ndef runMission():\n"
        "    api.executeBehavior('TAKE_OFF')\n    api.executeBehavior('LAND')\n",
        encoding="utf-8",
    )
    path = folder / "short.mcap"
    simulate(SessionConfig(mission=script, record=path))
    return path.read_bytes(), messages(path)


def is_subsequence(part: list[object], whole: list[object]) -> bool:
    rest = iter(whole)
    return all(any(item == other for other in rest) for item in part)


@settings(
    max_examples=80,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
    derandomize=True,
    database=None,
)
@given(data=st.data())
def test_damage_anywhere_is_reported_never_invented(
    small: tuple[bytes, list[tuple[str, int, bytes]]],
    tmp_path_factory: pytest.TempPathFactory,
    data: st.DataObject,
) -> None:
    """Zero a region, flip bytes, write garbage or cut, anywhere: every reader says the
    file is not whole (unless the damage missed every record), reads on after the damage,
    never yields a message the session did not record, and recover copies exactly what
    was read and says what it lacks."""
    original, whole = small
    raw = bytearray(original)
    how = data.draw(st.sampled_from(["zero", "flip", "garbage", "cut"]), "how")
    start = data.draw(st.integers(8, len(raw) - 1), "start")
    if how == "cut":
        raw = raw[:start]
    else:
        size = data.draw(st.integers(1, 4096), "size")
        end = min(len(raw), start + size)
        for i in range(start, end):
            if how == "zero":
                raw[i] = 0
            elif how == "flip":
                raw[i] ^= 0xFF
            else:
                raw[i] = data.draw(st.integers(0, 255))
    folder = tmp_path_factory.mktemp("case")
    path = folder / "damaged.mcap"
    path.write_bytes(bytes(raw))
    try:
        recording = open_recording(path)
        read = [(m.channel.topic, m.log_time_ns, m.data) for m in recording.messages()]
    except RecordingError as exc:  # the header itself is gone: one line
        assert "\n" not in str(exc)
        return
    end = recording.end
    assert is_subsequence(read, whole), "a message the session never recorded"
    if len(read) < len(whole):
        assert not recording.complete and recording.problem
    if end.expected_messages is not None:
        assert end.messages_read == len(read)
    try:  # replay's own selective reader agrees, or calls it unusable in one line
        run = read_run(path, require_commands=False)
    except RecordingError as exc:
        assert "\n" not in str(exc)
    else:
        if len(read) < len(whole):
            assert not run.outcome.complete and run.outcome.problem
    fixed = folder / "fixed.mcap"
    report = recover(path, fixed)
    assert report.messages == len(read)
    copy = open_recording(fixed)
    assert copy.complete
    assert [(m.channel.topic, m.log_time_ns, m.data) for m in copy.messages()] == read
    assert ("aeroexec_recover" in copy.metadata) is (not recording.complete)
