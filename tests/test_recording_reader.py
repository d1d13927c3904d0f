"""The reader: typed records, metadata, attachments, completeness; damaged and foreign
files; memory flat in the file size."""

from __future__ import annotations

import tracemalloc
from pathlib import Path

import pytest
from mcap.reader import make_reader

from aeroexec.errors import RecordingError
from aeroexec.executive.messages import ServiceCallRecord, TopicRecord
from aeroexec.mission import APPENDIX_C, SessionConfig, simulate
from aeroexec.recording import (
    RecordedCall,
    RecordedTopic,
    Recorder,
    open_recording,
)

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "recording"
TALKER = FIXTURES / "mcap_ros2_talker_zstd.mcap"
MSGTYPES = FIXTURES / "mcap_ros2_94_msgtypes_rosbags_rs.mcap"


@pytest.fixture(scope="module")
def session_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("rec") / "appendix_c.mcap"
    simulate(SessionConfig(mission=APPENDIX_C, record=path))
    return path


def _mcap_messages(path: Path) -> list[tuple[str, int, bytes]]:
    with open(path, "rb") as stream:
        return [
            (channel.topic, message.log_time, message.data)
            for _, channel, message in make_reader(stream).iter_messages(log_time_order=False)
        ]


def test_typed_records_match_what_mcap_reads(session_file: Path) -> None:
    recording = open_recording(session_file)
    records = list(recording.records())
    raw = _mcap_messages(session_file)
    assert [(r.topic, r.log_time_ns) for r in records] == [(t, lt) for t, lt, _ in raw]
    calls = [r for r in records if isinstance(r, RecordedCall)]
    topics = [r for r in records if isinstance(r, RecordedTopic)]
    assert len(calls) + len(topics) == len(records)
    first = next(c for c in calls if c.service == "activate_behavior")
    assert first.request == {"behavior": "TAKE_OFF", "arguments": {}}
    assert first.ok and first.error == "" and first.response["uid"] == 1
    assert first.caller == "mission" and first.topic == "/drone1/activate_behavior"
    event = next(t for t in topics if t.name == "behavior_event")
    assert event.topic == "/drone1/behavior_event"
    assert event.data["name"] == "TAKE_OFF" and event.data["code"] == "GOAL_ACHIEVED"
    assert {t.name for t in topics} >= {"vehicle/state", "vehicle/transform", "mission/command"}
    # A call made at the top has no parent_seq in the file; the reader gives None.
    assert first.parent_seq is None
    assert any(c.parent_seq == first.seq for c in calls)
    assert recording.notes == []


def test_records_are_frozen(session_file: Path) -> None:
    record = next(iter(open_recording(session_file).records()))
    with pytest.raises(AttributeError):
        record.log_time_ns = 5  # type: ignore[misc]


def test_metadata_attachments_and_completeness(session_file: Path) -> None:
    recording = open_recording(session_file)
    assert recording.complete and recording.problem is None
    assert recording.profile == "aeroexec" and recording.is_aeroexec
    assert recording.metadata["aeroexec"]["vehicle"] == "sim"
    mission = recording.attachment("mission.py")
    assert mission is not None and mission.text == Path(APPENDIX_C).read_text()
    assert mission.media_type == "text/x-python"
    assert recording.attachment("nope") is None
    survey = recording.survey()
    assert survey.message_count == len(_mcap_messages(session_file))
    assert survey.first_log_time_ns == 0 and survey.last_log_time_ns == 18_600_000_000


@pytest.mark.parametrize("fraction", [0.3, 0.55, 0.8, 0.97])
def test_truncated_file_reads_a_prefix_and_says_incomplete(
    session_file: Path, tmp_path: Path, fraction: float
) -> None:
    data = session_file.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(len(data) * fraction)])
    recording = open_recording(cut)
    got = [(m.channel.topic, m.log_time_ns, m.data) for m in recording.messages()]
    full = _mcap_messages(session_file)
    assert got == full[: len(got)]
    assert not recording.complete
    assert recording.problem is not None and "byte" in recording.problem
    if fraction >= 0.8:
        assert len(got) > 0.5 * len(full)


def test_file_cut_right_after_a_flushed_chunk_loses_nothing_before_it(tmp_path: Path) -> None:
    path = tmp_path / "f.mcap"
    recorder = Recorder(path, flush_interval_ns=10**18)
    for i in range(300):
        recorder.on_topic(TopicRecord("log", {"message": str(i)}, i))
    # 300 messages = 3 full chunks flushed; copy the file as a killed process leaves it
    partial = tmp_path / "partial.mcap"
    partial.write_bytes(path.read_bytes())
    recorder.close()
    recording = open_recording(partial)
    messages = [r.data["message"] for r in recording.records()]
    assert messages == [str(i) for i in range(300)]
    assert not recording.complete and "no footer" in (recording.problem or "")


def test_a_damaged_chunk_is_stepped_over_and_reported(session_file: Path, tmp_path: Path) -> None:
    data = bytearray(session_file.read_bytes())
    middle = len(data) // 2
    data[middle : middle + 64] = bytes(64)
    broken = tmp_path / "broken.mcap"
    broken.write_bytes(bytes(data))
    recording = open_recording(broken)
    got = [(m.channel.topic, m.log_time_ns, m.data) for m in recording.messages()]
    full = _mcap_messages(session_file)
    assert 0 < len(got) < len(full)
    # What was read is the whole stream less one run of messages: nothing invented.
    head = next(i for i, (a, b) in enumerate(zip(got, full, strict=False)) if a != b)
    lost = len(full) - len(got)
    assert got[:head] == full[:head]
    assert got[head:] == full[head + lost :]
    end = recording.end
    assert not recording.complete and recording.problem
    assert end.footer and len(end.damages) == 1
    assert end.expected_messages == len(full) and end.messages_read == len(got)
    assert end.damages[0].messages == lost
    assert f"{len(got)} of the {len(full)} messages read" in recording.problem


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"", "empty file"),
        (b"\x89MCA", "ends inside the MCAP magic"),
        (b"hello, this is not a recording at all", "not an MCAP file"),
        (b"\x89MCAP0\r\n", "ends before the MCAP header"),
        (b"\x89MCAP0\r\n\x05" + bytes(8), "not a header"),
    ],
)
def test_unreadable_files_raise_one_line_errors(
    tmp_path: Path, content: bytes, message: str
) -> None:
    path = tmp_path / "bad.mcap"
    path.write_bytes(content)
    with pytest.raises(RecordingError) as info:
        open_recording(path)
    text = str(info.value)
    assert text.startswith(f"{path}: error: ") and message in text and "\n" not in text


def test_missing_file_and_directory(tmp_path: Path) -> None:
    with pytest.raises(RecordingError, match="no such file"):
        open_recording(tmp_path / "absent.mcap")
    with pytest.raises(RecordingError, match="is a directory"):
        open_recording(tmp_path)


def test_foreign_ros2_file_counts_match_mcap_and_cdr_is_skipped_with_a_note() -> None:
    recording = open_recording(TALKER)
    assert recording.profile == "ros2" and not recording.is_aeroexec
    survey = recording.survey()
    with open(TALKER, "rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None and summary.statistics is not None
    expected = {channel.topic: 0 for channel in summary.channels.values()}
    for cid, count in summary.statistics.channel_message_counts.items():
        expected[summary.channels[cid].topic] = count
    assert survey.topic_counts() == expected
    assert expected == {"/topic": 10, "/rosout": 10, "/parameter_events": 0}
    assert recording.complete
    assert list(recording.records()) == []
    assert recording.notes == ["20 cdr message(s) not decoded (typed records need JSON)"]


def test_foreign_file_without_statistics_counts_match_mcap() -> None:
    recording = open_recording(MSGTYPES)
    counts = recording.survey().topic_counts()
    expected: dict[str, int] = {}
    for topic, _, _ in _mcap_messages(MSGTYPES):
        expected[topic] = expected.get(topic, 0) + 1
    assert counts == expected
    assert len(counts) == 94 and sum(counts.values()) == 188
    assert "rosbag2" in recording.metadata


def _write_log_file(path: Path, messages: int) -> None:
    with Recorder(path) as recorder:
        for i in range(messages):
            recorder.on_service_call(
                ServiceCallRecord(
                    i + 1,
                    0,  # nested: one message per call (no call_log line)
                    "mission",
                    "check_consistency",
                    {"behavior": "GO_TO_POINT", "active_behaviors": ["X" * 40]},
                    {"ok": True, "error": "", "inconsistent": []},
                    i * 1000,
                )
            )


def _peak_while_reading(path: Path) -> tuple[int, int]:
    tracemalloc.start()
    try:
        count = sum(1 for _ in open_recording(path).records())
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return count, peak


def test_reading_is_streaming_memory_flat_in_file_size(tmp_path: Path) -> None:
    small, large = tmp_path / "small.mcap", tmp_path / "large.mcap"
    _write_log_file(small, 2_000)
    _write_log_file(large, 40_000)
    count_small, peak_small = _peak_while_reading(small)
    count_large, peak_large = _peak_while_reading(large)
    assert (count_small, count_large) == (2_000, 40_000)
    # 20x the messages: a reader that kept them would need ~20x the memory.
    assert peak_large < 2 * peak_small + 256 * 1024
