"""Aerostack's behavior-tree missions (YAML `nodes:`), verified against their task
catalog: every node's task exists and is performed, its parameters fit, and the tree
runs as a sequence on the task coordinator's model (the files are Aerostack's own,
copied from the project's shared data)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.cli import app

BT = Path(__file__).resolve().parent / "fixtures" / "verifier" / "bt"
CATALOG = BT / "aerostack_behavior_catalog_tello.yaml"
TELLO = BT / "aerostack_bt_mission_tello.yaml"
AIRPLANE = BT / "aerostack_bt_mission_airplane_inspection.yaml"
runner = CliRunner()


def findings(*paths: Path | str, missions: tuple[Path, ...] = ()) -> list[dict]:
    args = ["verify", *map(str, paths), "-f", "json"]
    for mission in missions:
        args += ["-m", str(mission)]
    result = runner.invoke(app, args)
    document = json.loads(result.output)
    assert document["inputErrors"] == [], document["inputErrors"]
    return [
        f
        for f in document["findings"]
        if not f["file"].endswith("tello.yaml") or "bt_" in f["file"]
    ]


def about(found: list[dict], mission: Path) -> list[tuple[str, int, tuple[str, ...]]]:
    return [
        (f["rule"], f["line"], tuple(f["subjects"])) for f in found if f["file"] == str(mission)
    ]


def test_aerostack_missions_are_verified_against_their_catalog() -> None:
    found = findings(CATALOG, TELLO, AIRPLANE)
    # Every task exists and every parameter fits: only the sequence speaks.
    assert about(found, TELLO) == [
        ("AX716", 12, ("TAKE_OFF", "MOVE_VERTICAL")),
        ("AX716", 26, ("MOVE_VERTICAL", "ROTATE")),
        ("AX716", 35, ("ROTATE", "MOVE_AT_SPEED")),
    ]
    assert about(found, AIRPLANE) == [("AX716", 77, ("ROTATE", "FOLLOW_PATH"))]
    # The same through --mission.
    again = findings(CATALOG, missions=(TELLO,))
    assert about(again, TELLO) == about(found, TELLO)


def test_waiting_for_each_task_leaves_nothing_to_say(tmp_path: Path) -> None:
    mission = tmp_path / "waited.yaml"
    mission.write_text(
        TELLO.read_text().replace("wait_for_completion: false", "wait_for_completion: true")
    )
    assert about(findings(CATALOG, mission), mission) == []


@pytest.mark.parametrize(
    ("change", "rule", "subjects"),
    [
        (("task: MOVE_VERTICAL", "task: MOVE_VERTICALLY"), "AX701", ("MOVE_VERTICALLY",)),
        (('"distance: 1"', '"dist: 1"'), "AX702", ("MOVE_VERTICAL", "dist")),
        (('"distance: 1"', '"distance: 500"'), "AX703", ("MOVE_VERTICAL", "distance")),
        (
            ("\"direction: 'FORWARD'\"", "\"direction: 'UP'\""),
            "AX703",
            ("MOVE_AT_SPEED", "direction"),
        ),
        (('"distance: 1"', '"distance: [1"'), "AX702", ("MOVE_VERTICAL",)),
    ],
)
def test_a_node_that_does_not_fit_the_catalog(
    tmp_path: Path, change: tuple[str, str], rule: str, subjects: tuple[str, ...]
) -> None:
    mission = tmp_path / "bad.yaml"
    text = TELLO.read_text()
    assert change[0] in text
    mission.write_text(text.replace(*change))
    assert (rule, subjects) in [(r, s) for r, _, s in about(findings(CATALOG, mission), mission)]


def test_a_path_point_with_two_numbers_is_a_dimension_error(tmp_path: Path) -> None:
    mission = tmp_path / "bad.yaml"
    mission.write_text(AIRPLANE.read_text().replace("[[ -5.2,0,2]]", "[[ -5.2,0]]"))
    assert ("AX704", 87, ("FOLLOW_PATH", "path")) in about(findings(CATALOG, mission), mission)


def test_a_start_the_coordinator_rejects(tmp_path: Path) -> None:
    # TAKE_OFF's only behavior now needs a task no behavior performs.
    take_off = "- behavior: TAKE_OFF\n  package: basic_quadrotor_behaviors\n  task: TAKE_OFF\n"
    text = CATALOG.read_text()
    assert take_off in text
    catalog = tmp_path / "catalog.yaml"
    catalog.write_text(text.replace(take_off, take_off + "  requires:\n  - task: GIMBAL\n"))
    rejected = [f for f in findings(catalog, TELLO) if f["rule"] == "AX717"]
    assert [(f["line"], f["subjects"]) for f in rejected] == [(12, ["TAKE_OFF"])]
    assert "GIMBAL" in rejected[0]["message"]


def test_against_a_behavior_catalog_a_tree_gets_the_abstract_run_of_python_missions(
    tmp_path: Path,
) -> None:
    from aeroexec.catalog import DEFAULT_CATALOG

    tree = BT / "behavior_tree.yaml"
    assert about(findings(DEFAULT_CATALOG, missions=(tree,)), tree) == []
    # Not waiting for TAKE_OFF: GO_TO_POINT preempts it in the executive before the
    # vehicle flies, and is rejected — what the Python mission would get.
    hurried = tmp_path / "hurried.yaml"
    hurried.write_text(
        tree.read_text().replace(
            "task: TAKE_OFF\n    wait_for_completion: true",
            "task: TAKE_OFF\n    wait_for_completion: false",
        )
    )
    found = [(r, line, s) for r, line, s in about(findings(DEFAULT_CATALOG, hurried), hurried)]
    assert ("AX711", 19, ("GO_TO_POINT",)) in found
    message = next(
        f["message"]
        for f in findings(DEFAULT_CATALOG, hurried)
        if f["rule"] == "AX711" and f["line"] == 19
    )
    assert "12: activate TAKE_OFF; 19: execute GO_TO_POINT" in message


# -- witnesses of task catalogs (issue 30, point 6) -----------------------------------------
def test_task_witnesses_are_replayed_on_the_model_and_say_so() -> None:
    from aeroexec.catalog.formats import read_any_catalog
    from aeroexec.verifier import check_task_catalog
    from aeroexec.verifier.task_witness import FAILS, HOLDS

    tasks = Path(__file__).resolve().parent / "fixtures" / "verifier" / "tasks"
    witnessed = []
    for path in sorted(tasks.glob("AX8*.yaml")):
        catalog = read_any_catalog(path)
        witnessed += [f for f in check_task_catalog(catalog) if f.witness is not None]  # type: ignore[arg-type]
    assert len(witnessed) >= 5
    assert all(f.witness.caveat.endswith(HOLDS) for f in witnessed)  # type: ignore[union-attr]
    assert not any(FAILS in f.witness.caveat for f in witnessed)  # type: ignore[union-attr]
    shown = runner.invoke(app, ["verify", str(tasks / "AX814.yaml"), "--witness"])
    assert (
        "(replayed on the model of the 2021 task coordinator; `aeroexec run` runs" in shown.output
    )


def test_a_witness_the_model_does_not_give_is_marked() -> None:
    from aeroexec.catalog.formats import read_any_catalog
    from aeroexec.verifier.findings import Outcome, Step, Witness
    from aeroexec.verifier.task_model import TaskModel
    from aeroexec.verifier.task_witness import replays

    catalog = read_any_catalog(CATALOG)
    model = TaskModel(catalog)  # type: ignore[arg-type]
    take_off = (Step("TAKE_OFF", service="start_task"),)
    assert replays(model, Witness(take_off, Outcome.ALL_ACTIVE))
    assert not replays(model, Witness(take_off, Outcome.REJECTED))


@pytest.mark.parametrize(
    ("text", "error"),
    [
        ("nodes: 5\n", "1:8: error: 'nodes' must be a list of nodes"),
        (
            "nodes:\n  - node: 1\n    parent: 2\n  - node: 2\n    parent: 1\n",
            "2:5: error: node 1: its parents form a cycle",
        ),
        ("nodes:\n  - node: x\n", "2:5: error: a node needs 'node' (an integer)"),
        ("nodes:\n  - node: 1\n    parent: 7\n", "2:5: error: node 1: no parent node 7"),
        (
            "nodes:\n  - node: 1\n    parent: 0\n  - node: 1\n    parent: 0\n",
            "4:5: error: node 1 is defined twice",
        ),
    ],
)
def test_a_malformed_tree_is_one_line_and_exit_2(tmp_path: Path, text: str, error: str) -> None:
    mission = tmp_path / "bad.yaml"
    mission.write_text(text)
    result = runner.invoke(app, ["verify", str(CATALOG), "-m", str(mission)])
    assert result.exit_code == 2
    assert f"{mission}:{error}" in result.output


def test_a_tree_too_deep_to_follow_is_refused_quickly(tmp_path: Path) -> None:
    lines = ["nodes:"]
    for number in range(1, 50_001):  # a chain: walked once, not once per node
        lines += [f"  - node: {number}", f"    parent: {number - 1}", "    type: control_flow"]
    mission = tmp_path / "deep.yaml"
    mission.write_text("\n".join(lines) + "\n")
    result = runner.invoke(app, ["verify", str(CATALOG), "-m", str(mission)])
    assert result.exit_code == 2
    assert f"{mission}:602:5: error: node 201: the tree is nested deeper than 200 levels" in (
        result.output
    )


# -- control nodes as Aerostack's behavior-tree interpreter runs them ------------------------
def tree(*nodes: tuple[int, int, str, str, str | None, bool]) -> str:
    """A mission: (number, parent, type, subtype, task, wait_for_completion) per node."""
    lines = ["nodes:"]
    for number, parent, kind, subtype, task, wait in nodes:
        lines += [
            f"  - node: {number}",
            f"    name: n{number}",
            f"    type: {kind}",
            f"    subtype: {subtype}",
            f"    parent: {parent}",
        ]
        if task is not None:
            lines += [f"    task: {task}", f"    wait_for_completion: {str(wait).lower()}"]
    return "\n".join(lines) + "\n"


def task(number: int, parent: int, name: str, wait: bool = True) -> tuple:
    return (number, parent, "execution", "task", name, wait)


def control(number: int, parent: int, subtype: str) -> tuple:
    return (number, parent, "control_flow", subtype, None, True)


def test_a_fallback_that_takes_a_rejected_start_is_not_a_failed_mission(tmp_path: Path) -> None:
    # TAKE_OFF is always rejected by this catalog; a fallback tries HOVER then, which
    # the coordinator accepts: the mission goes on. The same start in a sequence fails
    # the mission (AX717).
    catalog = BT / "AX717_catalog.yaml"
    handled = tmp_path / "handled.yaml"
    handled.write_text(
        tree(
            control(1, 0, "sequence"),
            control(2, 1, "fallback"),
            task(3, 2, "TAKE_OFF"),
            task(4, 2, "HOVER"),
        )
    )
    assert [r for r, _, _ in about(findings(catalog, handled), handled)] == []
    unhandled = tmp_path / "unhandled.yaml"
    unhandled.write_text(tree(control(1, 0, "sequence"), task(2, 1, "TAKE_OFF")))
    assert [r for r, _, _ in about(findings(catalog, unhandled), unhandled)] == ["AX717"]
    # Under a fallback whose every child is rejected, the failure reaches the root.
    both = tmp_path / "both.yaml"
    both.write_text(tree(control(1, 0, "fallback"), task(2, 1, "TAKE_OFF"), task(3, 1, "TAKE_OFF")))
    assert ("AX717", ("TAKE_OFF",)) in [(r, s) for r, _, s in about(findings(catalog, both), both)]


def test_a_fallback_child_starts_from_what_the_failed_one_left(tmp_path: Path) -> None:
    # The first child starts TAKE_OFF without waiting, then fails (its MOVE_VERTICAL,
    # waited for, may fail). The fallback's second child then starts ROTATE while
    # TAKE_OFF still runs: the coordinator stops TAKE_OFF (AX716). Alternatives taken
    # from the fallback's own starting state would not see TAKE_OFF running.
    mission = tmp_path / "fallback.yaml"
    mission.write_text(
        tree(
            control(1, 0, "fallback"),
            control(2, 1, "sequence"),
            task(3, 2, "TAKE_OFF", wait=False),
            task(4, 2, "WAIT"),
            task(5, 1, "ROTATE"),
        ).replace("task: WAIT", 'task: WAIT\n    parameters: "duration: 1"')
    )
    found = about(findings(CATALOG, mission), mission)
    assert ("AX716", ("TAKE_OFF", "ROTATE")) in [(r, s) for r, _, s in found]
    # Waiting for TAKE_OFF: it ended before anything else started.
    waited = tmp_path / "waited.yaml"
    waited.write_text(
        mission.read_text().replace("wait_for_completion: false", "wait_for_completion: true")
    )
    assert about(findings(CATALOG, waited), waited) == []


def test_a_parallel_starts_its_tasks_together(tmp_path: Path) -> None:
    # Waited for or not, the children of a parallel start in the same tick: two
    # mutually exclusive tasks there stop each other; in a sequence, waited, they do not.
    parallel = tmp_path / "parallel.yaml"
    parallel.write_text(
        tree(control(1, 0, "parallel"), task(2, 1, "TAKE_OFF"), task(3, 1, "ROTATE"))
    )
    assert [(r, s) for r, _, s in about(findings(CATALOG, parallel), parallel)] == [
        ("AX716", ("TAKE_OFF", "ROTATE"))
    ]
    sequence = tmp_path / "sequence.yaml"
    sequence.write_text(parallel.read_text().replace("subtype: parallel", "subtype: sequence"))
    assert about(findings(CATALOG, sequence), sequence) == []
