"""The committed recording from aeroexec 0.1.0 still replays with zero differences.

recordings/appendix_c-v0.1.0.mcap stays as committed while the code evolves: a change
that alters what the Appendix C mission does (or breaks reading an older file) fails
here. If a change is intended, say so in review and re-record the fixture.
"""

from __future__ import annotations

import pytest
from test_replay_support import V010

from aeroexec.recording import open_recording
from aeroexec.replay import Mode, ReplayOptions, extract_outcome, replay_recording


def test_the_fixture_is_the_v010_appendix_c_recording() -> None:
    recording = open_recording(V010)
    assert recording.complete
    metadata = recording.metadata["aeroexec"]
    assert metadata["aeroexec_version"] == "0.1.0"
    assert metadata["mission"] == "appendix_c.py"
    outcome = extract_outcome(V010)
    assert len(outcome.commands) == 9
    assert [c.end_code for c in outcome.commands if c.activates] == [
        "GOAL_ACHIEVED",
        "INTERRUPTED",
        "GOAL_ACHIEVED",
        "GOAL_ACHIEVED",
        "GOAL_ACHIEVED",
        "GOAL_ACHIEVED",
        "GOAL_ACHIEVED",
    ]


@pytest.mark.parametrize("mode", [Mode.closed, Mode.open])
def test_v010_recording_replays_without_differences(mode: Mode) -> None:
    result = replay_recording(V010, ReplayOptions(mode=mode))
    assert result.error is None
    assert result.diff is not None
    assert result.diff.compared == 9
    assert [d.message for d in result.diff.differences] == []
