"""The mission folder follows Python: constant loops unroll (`range(n)`, `break`),
`try`/`except`/`finally` and `with` run their code on the ways Python runs it, names
are looked up in constant dicts, and a finding inside a helper names the call that
leads there.

Every correct mission of `fixtures/verifier/correct` is also flown by `aeroexec run`
against the bundled catalog: the run agrees that nothing is wrong (every behavior ends
GOAL_ACHIEVED or is inhibited), so a finding there would be a false positive.
"""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.catalog import DEFAULT_CATALOG, read_catalog
from aeroexec.cli import app
from aeroexec.verifier import Finding, check_mission, parse_mission

CORRECT = Path(__file__).resolve().parent / "fixtures" / "verifier" / "correct"
runner = CliRunner()


def findings(text: str, rule: str | None = None) -> list[Finding]:
    script = parse_mission(textwrap.dedent(text), "m.py")
    found = check_mission(script, read_catalog(DEFAULT_CATALOG))
    return [f for f in found if rule is None or f.rule == rule]


@pytest.mark.parametrize("mission", sorted(p.name for p in CORRECT.glob("*.py")))
def test_a_correct_mission_gets_no_finding_and_flies(mission: str) -> None:
    path = CORRECT / mission
    verified = runner.invoke(app, ["verify", str(DEFAULT_CATALOG), "-m", str(path), "-f", "json"])
    assert verified.exit_code == 0, verified.output
    about_mission = [f for f in json.loads(verified.output)["findings"] if f["file"] == str(path)]
    assert about_mission == []
    flown = runner.invoke(app, ["run", str(path), "-q", "-c", str(DEFAULT_CATALOG)])
    assert flown.exit_code == 0, flown.output
    summary = flown.output.strip().splitlines()[-1]
    assert "0 rejected" in summary
    assert "vehicle landed" in summary


def test_a_constant_range_runs_exactly_its_iterations() -> None:
    # Two take-offs in a row: the second is rejected, on the only path there is.
    [twice] = findings(
        """\
        from executive_engine_api import execute_behavior

        def runMission():
            for i in range(2):
                execute_behavior('TAKE_OFF')
            execute_behavior('LAND')
        """,
        "AX711",
    )
    assert (twice.line, twice.subjects) == (5, ("TAKE_OFF",))
    assert "loop" not in twice.message  # unrolled, not explored as a loop


def test_a_finally_that_does_not_inhibit_still_leaves_the_behavior_running() -> None:
    [left] = findings(
        """\
        from executive_engine_api import activate_behavior, execute_behavior

        def runMission():
            execute_behavior('TAKE_OFF')
            activate_behavior('PAY_ATTENTION')
            try:
                return
            finally:
                execute_behavior('LAND')
        """,
        "AX712",
    )
    assert "7: return; 6: finally; 9: execute LAND" in left.message


def test_a_jump_in_finally_replaces_the_return_in_flight() -> None:
    # The `finally` breaks out of the loop: the mission goes on after it, and LAND runs.
    found = findings(
        """\
        from executive_engine_api import execute_behavior

        def runMission():
            execute_behavior('TAKE_OFF')
            for n in range(1):
                try:
                    return
                finally:
                    break
            execute_behavior('LAND')
            execute_behavior('LAND')
        """,
        "AX711",
    )
    assert [(f.line, f.subjects) for f in found] == [(11, ("LAND",))]


def test_an_exception_a_handler_does_not_surely_catch_also_propagates() -> None:
    found = findings(
        """\
        from executive_engine_api import activate_behavior, execute_behavior, inhibit_behavior

        def runMission():
            execute_behavior('TAKE_OFF')
            try:
                raise ValueError('x')
            except KeyError:
                execute_behavior('LAND')
            execute_behavior('LAND')
        """,
        "AX711",
    )
    # Only the handled path reaches the second LAND, after the first.
    assert [(f.line, f.subjects) for f in found] == [(9, ("LAND",))]


def test_a_name_looked_up_in_a_dict_that_is_changed_is_not_trusted() -> None:
    found = findings(
        """\
        from executive_engine_api import execute_behavior

        NAMES = {'up': 'TAKE_OFF'}

        def runMission():
            NAMES['up'] = 'TAKE_OF'
            execute_behavior(NAMES['up'])
        """
    )
    assert [f.rule for f in found if f.rule.startswith("AX70")] == ["AX708"]


def test_a_misspelled_name_in_a_dict_is_reported_where_the_call_is() -> None:
    [unknown] = findings(
        """\
        from executive_engine_api import execute_behavior

        NAMES = {'up': 'TAKE_OF'}

        def runMission():
            execute_behavior(NAMES['up'])
        """,
        "AX701",
    )
    assert (unknown.line, unknown.subjects) == (6, ("TAKE_OF",))


HELPER = """\
from executive_engine_api import execute_behavior


def fly(name):
    execute_behavior(name, coordinates=[1, 1])


def go(name):
    fly(name)


def runMission():
    execute_behavior('TAKE_OFF')
    go('GO_TO_POINT')
    execute_behavior('LAND')
"""


def test_a_finding_in_a_helper_names_the_calls_that_lead_there(tmp_path: Path) -> None:
    mission = tmp_path / "m.py"
    mission.write_text(HELPER)
    base = ["verify", str(DEFAULT_CATALOG), "-m", str(mission), "--min-severity", "error"]
    text = runner.invoke(app, base)
    lines = [line for line in text.output.splitlines() if line.startswith(str(mission))]
    assert lines == [
        f"{mission}:5:28: error AX704 execute_behavior('GO_TO_POINT'): COORDINATES needs 3 "
        "numbers in [-100, 100], got 2 values",
        f"{mission}:9:5: note: in fly(), called from here",
        f"{mission}:14:5: note: in go(), called from here",
    ]
    [finding] = json.loads(runner.invoke(app, [*base, "-f", "json"]).output)["findings"]
    assert [(r["line"], r["message"]) for r in finding["related"]] == [
        (9, "in fly(), called from here"),
        (14, "in go(), called from here"),
    ]
    sarif = json.loads(runner.invoke(app, [*base, "-f", "sarif"]).output)
    [result] = [r for r in sarif["runs"][0]["results"] if r["ruleId"] == "AX704"]
    related = result["relatedLocations"]
    assert [r["physicalLocation"]["region"]["startLine"] for r in related] == [9, 14]


def test_a_sequence_finding_in_a_helper_names_its_call_site_too() -> None:
    [rejected] = findings(
        """\
        from executive_engine_api import execute_behavior

        def land():
            execute_behavior('LAND')

        def runMission():
            land()
        """,
        "AX711",
    )
    assert rejected.line == 4
    assert [(r.line, r.message) for r in rejected.related] == [(7, "in land(), called from here")]


def test_a_with_body_finding_names_no_context_manager_as_its_caller() -> None:
    [rejected] = findings(
        """\
        from contextlib import contextmanager

        from executive_engine_api import activate_behavior, execute_behavior, inhibit_behavior

        @contextmanager
        def attention():
            activate_behavior('PAY_ATTENTION')
            try:
                yield
            finally:
                inhibit_behavior('PAY_ATTENTION')

        def runMission():
            with attention():
                execute_behavior('LAND')
        """,
        "AX711",
    )
    assert (rejected.line, rejected.related) == (15, ())
    assert "7: activate PAY_ATTENTION; 15: execute LAND" in rejected.message


def test_a_while_loop_on_a_counter_runs_exactly_its_iterations() -> None:
    [twice] = findings(
        """\
        from executive_engine_api import execute_behavior

        def runMission():
            n = 0
            while n < 2:
                execute_behavior('TAKE_OFF')
                n += 1
            execute_behavior('LAND')
        """,
        "AX711",
    )
    assert twice.line == 6 and "iteration #2" in twice.message
    # A condition the run decides is still explored as a loop.
    looping = findings(
        """\
        from executive_engine_api import execute_behavior, true_belief

        def runMission():
            n = 0
            while n < 2 and true_belief('battery(high)'):
                execute_behavior('TAKE_OFF')
                n += 1
        """,
        "AX711",
    )
    assert [f.line for f in looping] == [6]
    assert "loop #2" in looping[0].message


def test_nested_constant_loops_unroll_within_a_budget_and_say_so() -> None:
    # 64 x 64 x 64 iterations would be 262,144 calls to fold: beyond the budget the inner
    # loops stay loops, and AX715 names them.
    found = findings(
        """\
        from executive_engine_api import execute_behavior

        def runMission():
            execute_behavior('TAKE_OFF')
            for a in range(64):
                for b in range(64):
                    for c in range(64):
                        execute_behavior('ROTATE', angle=c)
        """
    )
    [bounded] = [f for f in found if f.rule == "AX715"]
    assert "the loop at line 7 left as a loop (1000 iterations unrolled)" in bounded.message
    assert [f for f in found if f.severity.value == "error"] == []


def test_a_return_inside_a_with_body_runs_the_helpers_finally_then_leaves() -> None:
    found = findings(
        """\
        from contextlib import contextmanager

        from executive_engine_api import execute_behavior

        @contextmanager
        def airborne():
            execute_behavior('TAKE_OFF')
            try:
                yield
            finally:
                execute_behavior('LAND')

        def runMission():
            for leg in range(2):
                with airborne() as flight:
                    execute_behavior('GO_TO_POINT', coordinates=[leg, 1, 1])
                    if leg == 0:
                        continue
                    return
            execute_behavior('LAND')
        """
    )
    # Each leg takes off and lands again (the finally on `continue` and on `return`);
    # the LAND after the loop is never reached, so it is not a landing while landed.
    assert [f for f in found if f.severity.value != "info"] == []
