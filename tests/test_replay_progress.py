"""One big replay shows how far it is (issue 17): its read in bytes of the file, then its
re-run in the recording's own time -- each bar full at the end and moving along the way,
in every loop, and without changing what the replay finds."""

from __future__ import annotations

from pathlib import Path

import pytest
from progress_bars import Bars

from aeroexec.cli import replay_cmd
from aeroexec.replay.collect import read_run
from aeroexec.replay.engine import Mode, ReplayOptions, replay_recording

REPO = Path(__file__).resolve().parent.parent
RECORDING = REPO / "recordings" / "appendix_c-v0.1.0.mcap"


@pytest.mark.parametrize(
    ("mode", "trust"),
    [(Mode.closed, False), (Mode.closed, True), (Mode.open, False)],
    ids=["closed-recorded-commands", "closed-recorded-script", "open"],
)
def test_a_replay_reports_its_read_then_its_rerun(mode: Mode, trust: bool) -> None:
    options = ReplayOptions(mode=mode, trust_recording=trust)
    bars = Bars()
    with_bars = replay_recording(RECORDING, options, bars)
    reading, replaying = bars.bars
    assert reading.description == f"reading {RECORDING.name}"
    assert reading.total == reading.done == RECORDING.stat().st_size
    outcome = read_run(RECORDING).outcome
    span_ms = ((outcome.end_ns or 0) - (outcome.start_ns or 0)) // 1_000_000
    assert replaying.description == f"replaying {RECORDING.name}"
    assert replaying.total == replaying.done == span_ms > 10_000  # Appendix C: minutes
    # Along the way, never back and never standing still on a call.
    assert len(reading.steps) > 1 and len(replaying.steps) > 20
    assert min(reading.steps + replaying.steps) > 0
    # Watching changes nothing the replay finds.
    assert with_bars == replay_recording(RECORDING, options)


def test_only_one_big_recording_on_a_terminal_gets_the_bars(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    small = str(RECORDING)
    big = tmp_path / "big.mcap"
    big.write_bytes(b"\0" * replay_cmd.ONE_BIG_REPLAY_BYTES)
    monkeypatch.setattr(replay_cmd.sys.stderr, "isatty", lambda: True)
    assert replay_cmd._one_big_replay([str(big)], "local") is not None
    assert replay_cmd._one_big_replay([small], "local") is None  # done in a blink
    assert replay_cmd._one_big_replay([str(big), str(big)], "local") is None  # files count
    assert replay_cmd._one_big_replay([str(big)], "ray") is None  # runs elsewhere
    assert replay_cmd._one_big_replay(["https://example.org/big.mcap"], "local") is None
    monkeypatch.setattr(replay_cmd.sys.stderr, "isatty", lambda: False)
    assert replay_cmd._one_big_replay([str(big)], "local") is None
