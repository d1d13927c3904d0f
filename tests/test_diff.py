"""The outcome diff (aligned by mission command, tolerances, wording) and `aeroexec diff`."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from dataclasses import replace
from pathlib import Path

import pytest
from test_replay_support import APPENDIX_C, WATCH, catalog_for, record
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.replay import (
    CommandOutcome,
    FinalState,
    RunOutcome,
    Tolerance,
    Transition,
    diff_outcomes,
)

S = 1_000_000_000
runner = CliRunner()


def go(index: int, point: list[float], t: float, took: float, **changes: object) -> CommandOutcome:
    command = CommandOutcome(
        index=index,
        time_ns=round(t * S),
        command="execute_behavior",
        behavior="GO_TO_POINT",
        arguments={"COORDINATES": point},
        accepted=True,
        uid=index + 1,
        end_code="GOAL_ACHIEVED",
        end_ns=round((t + took) * S),
        processes=(Transition("planner", True), Transition("planner", False)),
    )
    return replace(command, **changes)  # type: ignore[arg-type]


def run(*commands: CommandOutcome, at: tuple[float, float, float] = (0, 0, 0)) -> RunOutcome:
    return RunOutcome(
        source="run.mcap",
        commands=commands,
        final_state=FinalState(at, False, 0.9, 10 * S),
    )


def found(base: RunOutcome, new: RunOutcome, **kw: object) -> list[tuple[int | None, str]]:
    result = diff_outcomes(base, new, **kw)  # type: ignore[arg-type]
    return [(d.command, d.kind) for d in result.differences]


def test_identical_runs_are_equal() -> None:
    base = run(go(0, [1, 0, 1], 0, 2), go(1, [2, 0, 1], 2, 2))
    result = diff_outcomes(base, base)
    assert result.equal
    assert result.compared == 2


def test_end_time_tolerance_is_inclusive_and_settable() -> None:
    base = run(go(0, [1, 0, 1], 0, 2.0))
    assert found(base, run(go(0, [1, 0, 1], 0, 2.5))) == []  # 0.5 s: within the default
    assert found(base, run(go(0, [1, 0, 1], 0, 2.6))) == [(0, "end_time")]
    assert found(base, run(go(0, [1, 0, 1], 0, 2.6)), tolerance=Tolerance(time_s=1.0)) == []
    # Only the duration counts: a command issued later (an earlier one took longer) is
    # not a difference of its own.
    assert found(base, run(go(0, [1, 0, 1], 7.0, 2.0))) == []


def test_position_tolerance() -> None:
    base = run(go(0, [1, 0, 1], 0, 2), at=(1.0, 0.0, 0.0))
    assert found(base, run(go(0, [1, 0, 1], 0, 2), at=(1.05, 0.0, 0.0))) == []
    assert found(base, run(go(0, [1, 0, 1], 0, 2), at=(1.2, 0.0, 0.0))) == [(None, "final_state")]
    near = run(go(0, [1, 0, 1], 0, 2), at=(1.2, 0.0, 0.0))
    assert found(base, near, tolerance=Tolerance(position_m=0.5)) == []
    assert found(base, near, compare_state=False) == []


def test_alignment_reports_commands_in_only_one_run() -> None:
    """A command missing from the middle does not shift the comparison of the rest: the
    LANDs (#3 and #2) are matched and equal; the arguments of a matched command are
    compared; a command of one run only is named with its index in that run."""
    land = CommandOutcome(3, 6 * S, "execute_behavior", "LAND", accepted=True, uid=9)
    hover = CommandOutcome(3, 6 * S, "execute_behavior", "KEEP_HOVERING", accepted=True, uid=8)
    base = run(go(0, [1, 0, 1], 0, 2), go(1, [2, 0, 1], 2, 2), go(2, [3, 0, 1], 4, 2), land)
    new = run(go(0, [1, 0, 1], 0, 2), go(1, [5, 0, 1], 2, 2), replace(land, index=2), hover)
    result = diff_outcomes(base, new, base_name="A", new_name="B")
    assert [(d.kind, d.base_index, d.new_index) for d in result.differences] == [
        ("arguments", 1, 1),
        ("only_in_base", 2, None),
        ("only_in_new", None, 3),
    ]
    assert result.compared == 3
    assert [d.message for d in result.differences] == [
        "#1 GO_TO_POINT COORDINATES=[2, 0, 1] now has arguments COORDINATES=[5, 0, 1] "
        "(was COORDINATES=[2, 0, 1])",
        "#2 GO_TO_POINT COORDINATES=[3, 0, 1] only in A: the mission took another path",
        "#3 KEEP_HOVERING only in B: the mission took another path",
    ]


def test_a_new_rejection_is_reported_alone() -> None:
    base = run(go(0, [3, 0, 1], 0, 2))
    new = run(
        go(
            0,
            [3, 0, 1],
            0,
            2,
            accepted=False,
            error="too far",
            end_code=None,
            end_ns=None,
            processes=(),
        )
    )
    result = diff_outcomes(base, new)
    assert [d.message for d in result.differences] == [
        "#0 GO_TO_POINT COORDINATES=[3, 0, 1] now rejected: too far"
    ]


def test_interrupted_compares_who_not_when() -> None:
    hover = CommandOutcome(
        0,
        0,
        "activate_behavior",
        "PAY_ATTENTION",
        accepted=True,
        uid=1,
        end_code="INTERRUPTED",
        end_ns=5 * S,
        end_detail="inhibited",
    )
    later = replace(hover, end_ns=9 * S)
    assert found(run(hover), run(later)) == []
    preempted = replace(hover, end_ns=1 * S, end_detail="preempted by GO_TO_POINT")
    result = diff_outcomes(run(hover), run(preempted))
    assert [d.message for d in result.differences] == [
        "#0 activate PAY_ATTENTION now ends INTERRUPTED after 1.0 s, preempted by GO_TO_POINT "
        "(was inhibited after 5.0 s)"
    ]


def test_transition_wording() -> None:
    up, down = Transition("p", True), Transition("p", False)
    base = run(go(0, [1, 0, 1], 0, 2, processes=(up, down)))
    reordered = run(go(0, [1, 0, 1], 0, 2, processes=(down, up)))
    twice = run(go(0, [1, 0, 1], 0, 2, processes=(up, down, up, down)))
    assert (
        diff_outcomes(base, reordered)
        .differences[0]
        .message.endswith("processes: same changes in another order: -p +p (was +p -p)")
    )
    assert (
        diff_outcomes(base, twice)
        .differences[0]
        .message.endswith("processes: now starts p; now stops p")
    )
    assert (
        diff_outcomes(twice, base)
        .differences[0]
        .message.endswith("processes: no longer starts p; no longer stops p")
    )


def test_initialization_differences() -> None:
    base = replace(run(), initial_processes=(Transition("odometry", True),))
    new = replace(run(), initial_processes=(Transition("odometry", True), Transition("gps", True)))
    result = diff_outcomes(base, new)
    assert [(d.command, d.kind, d.message) for d in result.differences] == [
        (None, "initialization", "initialization processes: now starts gps")
    ]


def test_tolerance_refuses_nonsense() -> None:
    with pytest.raises(ValueError):
        Tolerance(time_s=-1)
    with pytest.raises(ValueError):
        Tolerance(position_m=float("nan"))


def test_json_form() -> None:
    base = run(go(0, [1, 0, 1], 0, 2.0))
    document = diff_outcomes(base, run(go(0, [1, 0, 1], 0, 3.0))).as_dict()
    assert document["equal"] is False
    assert document["differences"] == [
        {
            "command": 0,
            "label": "#0 GO_TO_POINT COORDINATES=[1, 0, 1]",
            "kind": "end_time",
            "message": "#0 GO_TO_POINT COORDINATES=[1, 0, 1] now ends GOAL_ACHIEVED after 3.0 s "
            "(was 2.0 s; tolerance 0.5 s)",
            "base_index": 0,
            "new_index": 0,
            "line": None,  # no mission script named
        }
    ]


# -- aeroexec diff --------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def pair(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    work = tmp_path_factory.mktemp("diff")
    base = record(work / "base.mcap", APPENDIX_C)
    again = record(work / "again.mcap", APPENDIX_C)
    narrow = record(work / "narrow.mcap", APPENDIX_C, catalog_for(work, "narrowed"))
    return base, again, narrow


def cli(*args: str) -> tuple[int, str, str]:
    result = runner.invoke(app, ["diff", *args])
    assert result.exception is None or isinstance(result.exception, SystemExit)
    return result.exit_code, result.stdout, result.stderr


def test_diff_equal_recordings(pair: tuple[Path, Path, Path]) -> None:
    base, again, _ = pair
    code, out, _ = cli(str(base), str(again))
    assert code == 0
    assert out.strip() == f"{base} -> {again}: no differences (9 commands compared)"


def test_diff_text(pair: tuple[Path, Path, Path]) -> None:
    base, _, narrow = pair
    code, out, _ = cli(str(base), str(narrow))
    assert code == 1
    assert out.splitlines() == [
        f"{base} -> {narrow}: 2 differences (9 commands compared)",
        "  #4 GO_TO_POINT coordinates=[3, 5.5, 1.3] now rejected: GO_TO_POINT: "
        "COORDINATES needs 3 numbers "
        "in [-2, 2], got [3, 5.5, 1.3] (3 is outside)",
        "  #6 GO_TO_POINT coordinates=[0, 0, 1.41] now ends GOAL_ACHIEVED after 0.1 s (was 5.3 s; "
        "tolerance 0.5 s)",
    ]


def test_diff_json_and_tolerance(pair: tuple[Path, Path, Path]) -> None:
    base, _, narrow = pair
    code, out, _ = cli(str(base), str(narrow), "--format", "json", "--tolerance", "10")
    assert code == 1
    document = json.loads(out)
    assert document["equal"] is False
    assert [(d["command"], d["kind"]) for d in document["differences"]] == [(4, "accepted")]
    assert document["tolerance"]["time_s"] == 10


def test_diff_junit(pair: tuple[Path, Path, Path]) -> None:
    base, again, narrow = pair
    _, out, _ = cli(str(base), str(narrow), "--format", "junit")
    root = ET.fromstring(out)
    assert root.tag == "testsuites" and (root.get("tests"), root.get("failures")) == ("1", "1")
    (suite,) = root.findall("testsuite")
    assert (suite.get("tests"), suite.get("failures")) == ("1", "1")
    (case,) = suite.findall("testcase")
    failure = case.find("failure")
    assert failure is not None and "#4 GO_TO_POINT" in (failure.text or "")
    _, out, _ = cli(str(base), str(again), "--format", "junit")
    (case,) = ET.fromstring(out).findall("testsuite/testcase")
    assert case.find("failure") is None


def test_diff_different_missions_take_other_paths(
    pair: tuple[Path, Path, Path], tmp_path: Path
) -> None:
    base, _, _ = pair
    other = record(tmp_path / "watch.mcap", WATCH)
    code, out, _ = cli(str(base), str(other), "--format", "json")
    assert code == 1
    kinds = {d["kind"] for d in json.loads(out)["differences"]}
    assert {"only_in_base", "only_in_new"} <= kinds


def test_diff_bad_input(pair: tuple[Path, Path, Path], tmp_path: Path) -> None:
    base, _, _ = pair
    code, out, err = cli(str(base), str(tmp_path / "missing.mcap"))
    assert code == 2
    assert out == ""
    assert err.strip() == f"{tmp_path / 'missing.mcap'}: error: no such file"
