"""Reading recordings for replay: the selective streaming pass, damage, flat memory."""

from __future__ import annotations

import tracemalloc
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap.records import Message
from test_replay_support import APPENDIX_C, SURVEY, WATCH, record, record_live_like

import aeroexec.replay.source as source_module
from aeroexec.recording import RecordedCall, open_recording
from aeroexec.recording.scan import RecordScanner
from aeroexec.replay import Mode, ReplayOptions, extract_outcome, read_run, replay_recording
from aeroexec.replay.collect import STATE_TOPIC, TOPICS, OutcomeBuilder
from aeroexec.replay.outcome import RunOutcome

HOVER = """
import executive_engine_api as api

def runMission():
    api.executeBehavior('TAKE_OFF')
    api.executeBehavior('KEEP_HOVERING', duration={seconds})
    api.executeBehavior('LAND')
"""


@pytest.fixture(scope="module")
def work(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("replay_stream")


@pytest.fixture(scope="module")
def recs(work: Path) -> dict[str, Path]:
    return {
        "appendix_c": record(work / "appendix_c.mcap", APPENDIX_C),
        "survey": record(work / "survey.mcap", SURVEY),
        "watch": record(work / "watch.mcap", WATCH),
        "live": record_live_like(work / "live.mcap", start_s=50.0),
    }


def hover_recording(work: Path, seconds: int) -> Path:
    mission = work / f"hover{seconds}.py"
    mission.write_text(HOVER.format(seconds=seconds))
    return record(work / f"hover{seconds}.mcap", mission)


def outcome_from_full_read(path: Path) -> RunOutcome:
    """The same summary built from every record of the general-purpose reader."""
    builder = OutcomeBuilder()
    for item in open_recording(path).records():
        if isinstance(item, RecordedCall):
            builder.call(
                item.service, item.parent_seq, item.request, item.response, item.log_time_ns
            )
        elif item.name == STATE_TOPIC:
            builder.vehicle_state(item.data, item.log_time_ns)
        elif item.name in TOPICS:
            builder.topic(item.name, item.data, item.log_time_ns)
    return builder.outcome(str(path))


@pytest.mark.parametrize("name", ["appendix_c", "survey", "watch", "live"])
def test_selective_pass_sees_what_a_full_read_sees(recs: dict[str, Path], name: str) -> None:
    selective = extract_outcome(recs[name])
    full = outcome_from_full_read(recs[name])
    assert selective.commands == full.commands
    assert selective.initial_processes == full.initial_processes
    assert selective.initial_capabilities == full.initial_capabilities
    assert selective.final_state == full.final_state
    assert selective.complete


def test_chunks_without_wanted_channels_are_not_decoded(
    work: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # A two-minute hover: a simulated run's chunks are 100 messages each (no time bound),
    # and most hold only vehicle states and beliefs, none of replay's channels.
    path = hover_recording(work, 120)
    with open(path, "rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    chunks = len(summary.chunk_indexes)
    decoded = 0
    real = source_module.breakup_chunk

    def counting(*args: object, **kwargs: object) -> object:
        nonlocal decoded
        decoded += 1
        return real(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(source_module, "breakup_chunk", counting)
    outcome = extract_outcome(path)
    assert len(outcome.commands) == 3
    assert outcome.final_state is not None
    assert chunks >= 12 and 0 < decoded < chunks / 2, (decoded, chunks)


def test_horizon_cuts_both_commands_and_final_state(recs: dict[str, Path]) -> None:
    path = recs["appendix_c"]
    full = extract_outcome(path)
    cut_at = full.commands[4].time_ns + 2_000_000_000  # GO_TO_POINT #4 under way
    cut = extract_outcome(path, horizon_ns=cut_at)
    assert [c.key for c in cut.commands] == [c.key for c in full.commands[:5]]
    assert cut.commands[2] == full.commands[2]  # over before the cut: all there
    assert cut.commands[4].end_ns is None  # still flying at the cut
    assert cut.final_state is not None
    assert cut.final_state.time_ns < cut_at
    assert cut.end_ns is not None and cut.end_ns < cut_at


def test_truncated_file_is_read_up_to_the_cut(recs: dict[str, Path], work: Path) -> None:
    data = recs["survey"].read_bytes()
    path = work / "survey-cut.mcap"
    path.write_bytes(data[: len(data) // 2])
    run = read_run(path)
    assert not run.outcome.complete
    assert "incomplete" in (run.outcome.problem or "")
    assert 0 < len(run.outcome.commands) < 7
    assert run.text("mission.py") is not None  # attachments come first: still there


def test_a_corrupt_chunk_is_reported_and_comparisons_stop_before_it(
    recs: dict[str, Path], work: Path
) -> None:
    path = recs["appendix_c"]
    with open(path, "rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    command_channel = next(
        cid for cid, ch in summary.channels.items() if ch.topic.endswith("/mission/command")
    )
    commands_at = extract_outcome(path).commands[5].time_ns
    chunk = next(
        c
        for c in summary.chunk_indexes
        if command_channel in c.message_index_offsets and c.message_start_time >= commands_at
    )
    data = bytearray(path.read_bytes())
    data[chunk.chunk_start_offset + chunk.chunk_length - 5] ^= 0xFF
    broken = work / "corrupt.mcap"
    broken.write_bytes(bytes(data))
    run = read_run(broken)
    assert not run.outcome.complete
    assert run.outcome.problem == (
        f"1 damaged region: chunk at byte {chunk.chunk_start_offset}: CRC mismatch "
        f"(messages lost, log time {chunk.message_start_time / 1e9:.3f} .. "
        f"{chunk.message_end_time / 1e9:.3f} s)"
    )
    # The read goes on after the damaged chunk: every command but those it held...
    original = extract_outcome(path).commands
    held = [
        offset == chunk.chunk_start_offset
        for offset, record in RecordScanner(path).records()
        if isinstance(record, Message) and record.channel_id == command_channel
    ]
    lost = [c for c, inside in zip(original, held, strict=True) if inside]
    assert 1 <= len(lost) < len(original) - 5
    assert [c.time_ns for c in run.outcome.commands] == [
        c.time_ns for c in original if c not in lost
    ]
    # ...but comparisons stop before it: what it held is lost.
    assert run.outcome.intact_until_ns == chunk.message_start_time
    result = replay_recording(broken, ReplayOptions(trust_recording=True))
    assert result.diff is not None and result.diff.equal
    assert any(
        note.startswith("damaged recording (1 damaged region: chunk") for note in result.notes
    )


def _peak_kib(action: object) -> float:
    tracemalloc.start()
    try:
        action()  # type: ignore[operator]
        return tracemalloc.get_traced_memory()[1] / 1024
    finally:
        tracemalloc.stop()


def test_memory_is_flat_in_recording_length(work: Path) -> None:
    """One minute and eight minutes of hovering: the same few commands, 8x the messages.
    Reading, and replaying both ways, must not grow with the length."""
    short = hover_recording(work, 60)
    long = hover_recording(work, 480)
    # 8x the flight; the fixed part (the commands, the first scene) keeps the message
    # ratio a little below that
    messages = [open_recording(p).survey().message_count for p in (short, long)]
    assert messages[1] > 5 * messages[0]
    for label, action in {
        "read": lambda p: read_run(p),
        "closed": lambda p: replay_recording(p, ReplayOptions(mode=Mode.closed)),
        "open": lambda p: replay_recording(p, ReplayOptions(mode=Mode.open)),
    }.items():
        small = _peak_kib(lambda a=action: a(short))
        large = _peak_kib(lambda a=action: a(long))
        assert large < 1.5 * small + 64, (label, small, large)
