"""The import's bulk MCAP writer: what mcap's own readers see in its files."""

from __future__ import annotations

import io
import math
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap.stream_reader import StreamReader

from aeroexec.bags.derive import pose_in_frame
from aeroexec.bags.extract import Pose
from aeroexec.bags.mcapwriter import BulkMcapWriter
from aeroexec.recording.writer import pose_message


def _write(compression: str, chunk_size: int) -> bytes:
    stream = io.BytesIO()
    writer = BulkMcapWriter(stream, compression=compression, chunk_size=chunk_size)
    writer.start("aeroexec", "test")
    writer.add_metadata("aeroexec", {"clock": "wall"})
    writer.add_attachment("bag_mapping.yaml", "application/yaml", b"topics: []\n")
    schema = writer.register_schema("pkg/Msg", "ros1msg", b"string data\n")
    a = writer.register_channel("/ros1/a", "ros1", schema, {"topic": "/a"})
    b = writer.register_channel("/ros1/b", "ros1", schema, {})
    empty = writer.register_channel("/ros1/never", "ros1", schema, {})
    for i in range(1000):
        writer.add_message(a if i % 3 else b, 1_000 + i, bytes([i % 256]) * (i % 50), 1_000 + i, i)
    writer.finish()
    assert empty == 3
    return stream.getvalue()


@pytest.mark.parametrize("compression", ["lz4", "zstd", "none"])
@pytest.mark.parametrize("chunk_size", [256, 1024 * 1024])
def test_indexed_and_streamed_reads_agree(compression: str, chunk_size: int) -> None:
    data = _write(compression, chunk_size)
    reader = make_reader(io.BytesIO(data), validate_crcs=True)
    summary = reader.get_summary()
    assert summary is not None and summary.statistics is not None
    assert summary.statistics.message_count == 1000
    assert summary.statistics.channel_message_counts == {1: 666, 2: 334}
    assert (summary.statistics.message_start_time, summary.statistics.message_end_time) == (
        1_000,
        1_999,
    )
    assert [c.topic for c in summary.channels.values()] == ["/ros1/a", "/ros1/b", "/ros1/never"]
    if chunk_size == 256:
        assert summary.statistics.chunk_count > 10
    indexed = [
        (channel.topic, m.log_time, m.sequence, m.data)
        for _, channel, m in reader.iter_messages(log_time_order=True)
    ]
    assert len(indexed) == 1000
    assert indexed[5] == ("/ros1/a", 1_005, 5, bytes([5]) * 5)
    assert indexed[6] == ("/ros1/b", 1_006, 6, bytes([6]) * 6)
    assert [t for _, t, _, _ in indexed] == list(range(1_000, 2_000))
    streamed = [r for r in StreamReader(io.BytesIO(data), validate_crcs=True).records]
    messages = [r for r in streamed if type(r).__name__ == "Message"]
    assert len(messages) == 1000
    assert [m.data for m in messages] == [d for _, _, _, d in indexed]
    assert reader.get_header().profile == "aeroexec"
    assert [a.name for a in reader.iter_attachments()] == ["bag_mapping.yaml"]
    assert [m.metadata for m in reader.iter_metadata()] == [{"clock": "wall"}]


def test_a_file_without_messages_is_still_valid(tmp_path: Path) -> None:
    stream = io.BytesIO()
    writer = BulkMcapWriter(stream)
    writer.start("aeroexec", "test")
    schema = writer.register_schema("pkg/Msg", "ros1msg", b"")
    writer.register_channel("/ros1/a", "ros1", schema, {})
    writer.finish()
    reader = make_reader(io.BytesIO(stream.getvalue()), validate_crcs=True)
    summary = reader.get_summary()
    assert summary is not None and summary.statistics is not None
    assert summary.statistics.message_count == 0
    assert [c.topic for c in summary.channels.values()] == ["/ros1/a"]


@pytest.mark.parametrize("yaw", [0.0, 1.2, -3.0])
def test_the_derived_pose_is_the_recorders(yaw: float) -> None:
    pose = Pose((1.5, -2.0, 0.7), yaw)
    state = {"position": list(pose.position), "yaw": yaw}
    assert pose_in_frame(pose, 1_234_567_890_123) == pose_message(state, 1_234_567_890_123)
    assert pose_in_frame(Pose((math.nan, 0.0, 0.0), 0.0), 0) is None
