"""Closed-loop replay: recorded missions re-simulated against changed catalogs.

Each test records a mission with the default catalog, replays it against a small edit
of catalog/default.yaml, and checks the exact list of differences (command index and
kind) plus the wording a reviewer reads.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from test_replay_support import (
    APPENDIX_C,
    RANDOM_MOTOR_WORLD,
    SURVEY,
    WATCH,
    catalog_for,
    edited_catalog,
    kinds,
    messages,
    record,
    record_live_like,
)

from aeroexec.replay import Mode, ReplayOptions, ReplayResult, extract_outcome, replay_recording


@pytest.fixture(scope="module")
def work(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("replay_closed")


@pytest.fixture(scope="module")
def recs(work: Path) -> dict[str, Path]:
    return {
        "appendix_c": record(work / "appendix_c.mcap", APPENDIX_C),
        "survey": record(work / "survey.mcap", SURVEY),
        "watch": record(work / "watch.mcap", WATCH),
    }


def replay(path: Path, catalog: Path | None = None, **options: Any) -> ReplayResult:
    """Replay one of this module's own recordings, running its stored script (these
    tests are about script replays; the untrusted default is tested below)."""
    options.setdefault("trust_recording", True)
    return replay_recording(
        path, ReplayOptions(catalog=str(catalog) if catalog else None, **options)
    )


# -- unchanged inputs ----------------------------------------------------------------------
@pytest.mark.parametrize(("name", "commands"), [("appendix_c", 9), ("survey", 7), ("watch", 10)])
def test_unchanged_catalog_gives_no_difference(
    recs: dict[str, Path], name: str, commands: int
) -> None:
    result = replay(recs[name])
    assert result.mode == "closed"  # simulated recordings default to closed loop
    assert result.catalog_recorded
    assert result.diff is not None
    assert result.diff.compared == commands  # every command was compared, not none
    assert result.diff.differences == ()
    assert result.equal


def test_replay_is_byte_identical_to_its_recording(recs: dict[str, Path], work: Path) -> None:
    """Same mission, catalog, world, seed and code: the same file, byte for byte (the
    replay's metadata is the session's own, so no key has to be left out)."""
    for name, path in recs.items():
        out = work / f"{name}.replayed.mcap"
        result = replay(path, output=str(out))
        assert result.equal
        assert out.read_bytes() == path.read_bytes(), name


def test_the_recorded_catalog_is_used_not_the_installed_one(work: Path) -> None:
    """Recorded with the narrowed catalog, replayed with no --catalog: still no
    difference, because the replay takes the catalog from the recording."""
    narrowed = catalog_for(work, "narrowed")
    path = record(work / "survey-narrowed.mcap", SURVEY, narrowed)
    result = replay(path)
    assert kinds(result) == []
    assert result.catalog == "narrowed.yaml"


def test_world_and_seed_come_from_the_recording(work: Path) -> None:
    """A world whose motor fails at a seeded random time: only the recorded world and
    seed reproduce the flight."""
    path = record(work / "random.mcap", APPENDIX_C, seed=1, world=RANDOM_MOTOR_WORLD)
    original = extract_outcome(path)
    assert original.commands[0].end_code != "GOAL_ACHIEVED"  # the seed-1 flight fails
    out = work / "random.replayed.mcap"
    result = replay(path, output=str(out))
    assert kinds(result) == []
    assert out.read_bytes() == path.read_bytes()


# -- changed catalogs: the exact differences ---------------------------------------------------
def test_narrowed_argument_range_rejects(recs: dict[str, Path], work: Path) -> None:
    result = replay(recs["appendix_c"], catalog_for(work, "narrowed"))
    assert kinds(result) == [(4, "accepted"), (6, "end_time")]
    assert messages(result)[0] == (
        "#4 GO_TO_POINT coordinates=[3, 5.5, 1.3] now rejected: GO_TO_POINT: COORDINATES needs 3 "
        "numbers in [-2, 2], got [3, 5.5, 1.3] (3 is outside)"
    )
    # The way home is now short: the drone never left.
    assert messages(result)[1].startswith(
        "#6 GO_TO_POINT coordinates=[0, 0, 1.41] now ends GOAL_ACHIEVED after 0.1 s (was 5.3 s;"
    )


def test_new_incompatibility_preempts(recs: dict[str, Path], work: Path) -> None:
    result = replay(recs["appendix_c"], catalog_for(work, "incompatible"))
    assert kinds(result) == [
        (1, "end_event"),
        (2, "preemptions"),
        (2, "capabilities"),
        (2, "processes"),
        (7, "accepted"),
    ]
    text = messages(result)
    assert text[0] == (
        "#1 activate PAY_ATTENTION_TO_VISUAL_MARKERS now ends INTERRUPTED after 0.0 s, "
        "preempted by GO_TO_POINT (was inhibited after 13.3 s)"
    )
    assert text[1] == (
        "#2 GO_TO_POINT relative_coordinates=[0, 0, 0.5] now preempts "
        "PAY_ATTENTION_TO_VISUAL_MARKERS"
    )
    assert text[2].endswith("capabilities: now releases VISUAL_MARKERS_RECOGNITION")
    assert text[3].endswith("processes: now stops droneArucoEyeROSModule")
    assert text[4] == (
        "#7 inhibit PAY_ATTENTION_TO_VISUAL_MARKERS now rejected: "
        "PAY_ATTENTION_TO_VISUAL_MARKERS is not active"
    )


def test_capability_processes_changed(recs: dict[str, Path], work: Path) -> None:
    result = replay(recs["appendix_c"], catalog_for(work, "processes"))
    assert kinds(result) == [(2, "processes"), (4, "processes"), (6, "processes")]
    for text in messages(result):
        assert text.endswith(
            "processes: no longer starts droneYawPlanner; no longer stops droneYawPlanner"
        )


def test_shortened_timeout_times_out(recs: dict[str, Path], work: Path) -> None:
    result = replay(recs["appendix_c"], catalog_for(work, "timeout"))
    assert kinds(result) == [(4, "end_event"), (6, "end_event"), (None, "final_state")]
    assert messages(result)[0] == (
        "#4 GO_TO_POINT coordinates=[3, 5.5, 1.3] now ends TIME_OUT after 3.0 s "
        "(was GOAL_ACHIEVED after 5.3 s): no result within 3 s"
    )
    # Cut short twice, the drone lands away from home.
    assert "landed (was (0.02, 0.04, 0.00) landed;" in messages(result)[2]


def test_removed_behavior_is_unknown(recs: dict[str, Path], work: Path) -> None:
    result = replay(recs["appendix_c"], catalog_for(work, "removed"))
    assert kinds(result) == [(5, "accepted")]
    assert messages(result) == ["#5 ROTATE angle=-90 now rejected: unknown behavior ROTATE"]


def test_a_rejection_for_another_reason(recs: dict[str, Path], work: Path) -> None:
    """watch.py's first LAND is refused on the ground in both runs, for different
    reasons once LAND is removed; its last LAND is now refused too."""
    no_land = edited_catalog(
        work,
        "no_land",
        [
            (
                "  - behavior: LAND\n    timeout: 15\n    recurrent: no\n"
                "    incompatible_lists: [motion_behaviors, rotation_behaviors]\n\n",
                "",
            ),
            ("      - LAND\n", ""),
        ],
    )
    result = replay(recs["watch"], no_land)
    assert kinds(result) == [(0, "error"), (9, "accepted"), (None, "final_state")]
    assert messages(result)[0] == (
        "#0 LAND rejected for another reason: unknown behavior LAND (was: LAND: not flying)"
    )


def test_a_shorter_hover_timeout_in_a_mission_with_beliefs(
    recs: dict[str, Path], work: Path
) -> None:
    short = edited_catalog(
        work,
        "short_hover",
        [
            (
                "    timeout: 1010\n    recurrent: no\n    incompatible_lists",
                "    timeout: 2\n    recurrent: no\n    incompatible_lists",
            )
        ],
    )
    result = replay(recs["watch"], short)
    assert kinds(result) == [(7, "end_event")]
    assert messages(result) == [
        "#7 KEEP_HOVERING duration=3 now ends TIME_OUT after 2.0 s (was GOAL_ACHIEVED "
        "after 3.0 s): "
        "no result within 2 s"
    ]


# -- the mission takes another path ----------------------------------------------------------
def test_commands_only_in_the_recording(recs: dict[str, Path], work: Path) -> None:
    result = replay(recs["survey"], catalog_for(work, "narrowed"))
    assert kinds(result) == [(4, "accepted"), (5, "only_in_base"), (None, "final_state")]
    assert messages(result)[1] == (
        "#5 GO_TO_POINT coordinates=[0, 0, 1.2] only in the recording: the mission took "
        "another path"
    )
    assert result.diff is not None
    assert result.diff.compared == 6


def test_commands_only_in_the_replay(work: Path) -> None:
    narrowed = catalog_for(work, "narrowed")
    path = record(work / "survey-narrow.mcap", SURVEY, narrowed)
    result = replay(path, edited_catalog(work, "default_copy"))
    assert kinds(result) == [(4, "accepted"), (5, "only_in_new"), (None, "final_state")]
    text = messages(result)
    assert text[0].startswith("#4 GO_TO_POINT coordinates=[4, 4, 1.2] now accepted (was rejected: ")
    assert text[1] == (
        "#5 GO_TO_POINT coordinates=[0, 0, 1.2] only in the replay: the mission took another path"
    )
    assert result.diff is not None
    assert result.diff.differences[1].new_index == 5
    assert result.diff.differences[1].base_index is None


def test_a_mission_that_now_raises(recs: dict[str, Path], work: Path) -> None:
    """TAKE_OFF made recurrent: execute_behavior refuses it at once and the mission
    raises; every later command exists only in the recording."""
    recurrent = edited_catalog(
        work,
        "recurrent_takeoff",
        [
            (
                "  - behavior: TAKE_OFF\n    timeout: 15\n    recurrent: no",
                "  - behavior: TAKE_OFF\n    timeout: 15\n    recurrent: yes",
            )
        ],
    )
    result = replay(recs["appendix_c"], recurrent)
    assert kinds(result) == [
        (0, "accepted"),
        *[(i, "only_in_base") for i in range(1, 9)],
        (None, "final_state"),
    ]
    assert messages(result)[0] == (
        "#0 TAKE_OFF now refused by the mission API: the executive never saw it"
    )
    assert any(
        "the replayed mission raised at " in note and "recurrent" in note for note in result.notes
    )


# -- a recording without its script ---------------------------------------------------------------
def test_without_script_the_command_stream_is_replayed(work: Path) -> None:
    path = record_live_like(work / "live.mcap", start_s=1000.0)
    same = replay(path, mode=Mode.closed)
    assert same.mode == "closed"
    assert kinds(same) == []
    assert any("no mission.py attachment" in note for note in same.notes)
    changed = replay(path, catalog_for(work, "removed"), mode=Mode.closed)
    assert kinds(changed) == [(3, "accepted")]
    assert messages(changed) == ["#3 ROTATE angle=90 now rejected: unknown behavior ROTATE"]
