"""Missions as sequences: folding non-literal calls, the abstract run on the executive,
paths through branches and loops, and the hostile nesting Python's parser rejects.

The sequence findings are checked against what really happens: the same fixture missions
are flown in the simulator with the standard behavior library (`simulate`, what
`aeroexec run` does), and the activation the verifier says is rejected is rejected
there, for the reason it gives.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.behaviors import STANDARD_LIBRARY
from aeroexec.catalog import DEFAULT_CATALOG, read_catalog
from aeroexec.cli import app
from aeroexec.errors import MissionError
from aeroexec.executive import Executive
from aeroexec.executive.behavior import FlightState
from aeroexec.mission import SessionConfig, simulate
from aeroexec.vehicles.base import VehicleState
from aeroexec.vehicles.null import NullVehicle
from aeroexec.verifier import Finding, check_mission, parse_mission

MISSIONS = Path(__file__).resolve().parent / "fixtures" / "verifier" / "missions"
SEQUENCE_CATALOG = MISSIONS / "sequence_catalog.yaml"
runner = CliRunner()


def mission_findings(
    text: str, catalog: Path = SEQUENCE_CATALOG, rule: str | None = None
) -> list[Finding]:
    script = parse_mission(textwrap.dedent(text), "m.py")
    found = check_mission(script, read_catalog(catalog))
    return [f for f in found if rule is None or f.rule == rule]


# -- folding: calls that are not literal ------------------------------------------------
def test_names_in_variables_loops_helpers_and_aliases_are_checked() -> None:
    found = mission_findings(
        """\
        import executive_engine_api as api
        from executive_engine_api import executeBehavior as go

        SECOND = 'LANDD'
        fly = api.executeBehavior


        def step(name, **arguments):
            return go(name, **arguments)


        def runMission():
            name = 'TAKE_OF'
            api.executeBehavior(name)
            for behavior in ['ROTATTE', 'TAKE_OFF']:
                step(behavior)
            fly(SECOND)
            go(f"GO_TO_{'PIONT'}")
        """,
        DEFAULT_CATALOG,
        "AX701",
    )
    assert [(f.line, f.subjects[0]) for f in found] == [
        (9, "ROTATTE"),  # inside the helper, reached from the loop
        (14, "TAKE_OF"),
        (17, "LANDD"),
        (18, "GO_TO_PIONT"),
    ]


def test_calls_that_depend_on_the_run_are_counted_with_their_lines() -> None:
    [info] = mission_findings(
        """\
        import executive_engine_api as api


        def runMission():
            ok, answer = api.consultBelief('plan(?A, ?B)')
            api.executeBehavior(answer['A'])
            for name in answer['B']:
                api.activateBehavior(name)
            api.executeBehavior('TAKE_OFF')
        """,
        rule="AX708",
    )
    assert info.severity.value == "info"
    assert info.message.startswith("2 calls not checked")
    assert "(lines 6, 8)" in info.message


def test_a_script_without_an_entry_point_is_an_error() -> None:
    [error] = mission_findings("import executive_engine_api as api\n", rule="AX707")
    assert (error.line, error.column) == (1, 1)
    assert "runMission(), run_mission(), main()" in error.message


# -- the sequence checks, against the real simulator ------------------------------------
def activations(fixture: str):
    # The catalog's extra recurrent behaviors (MONITOR_BATTERY, ...) have no code: stand-ins.
    config = SessionConfig(
        mission=MISSIONS / fixture, catalog=SEQUENCE_CATALOG, allow_unimplemented=True
    )
    result = simulate(config)
    return result.activations


def test_preempted_inhibit_agrees_with_the_simulator() -> None:
    [finding] = mission_findings((MISSIONS / "AX709.py").read_text(), rule="AX709")
    assert "ROTATE preempted it at line 8" in finding.message
    go = next(a for a in activations("AX709.py") if a.behavior == "GO_TO_POINT")
    assert (go.end_code, go.detail) == ("INTERRUPTED", "preempted by ROTATE")


def test_capability_conflict_agrees_with_the_simulator() -> None:
    [finding] = mission_findings((MISSIONS / "AX710.py").read_text(), rule="AX710")
    assert "conflicts with active capability FLIGHT_CONTROL (held by GO_TO_POINT)" in (
        finding.message
    )
    follow = next(a for a in activations("AX710.py") if a.behavior == "FOLLOW_OBJECT_IMAGE")
    assert not follow.accepted
    assert "conflicts with active capability FLIGHT_CONTROL" in follow.error


def test_wrong_flight_state_agrees_with_the_simulator() -> None:
    found = mission_findings((MISSIONS / "AX711.py").read_text(), rule="AX711")
    assert [(f.line, f.subjects[0]) for f in found] == [
        (6, "GO_TO_POINT"),
        (8, "TAKE_OFF"),
        (10, "ROTATE"),
    ]
    rejected = [(a.behavior, a.error) for a in activations("AX711.py") if not a.accepted]
    assert [b for b, _ in rejected] == ["GO_TO_POINT", "TAKE_OFF", "ROTATE"]
    assert "not flying" in rejected[0][1] and "already flying" in rejected[1][1]


def test_land_while_needed_agrees_with_the_simulator() -> None:
    [finding] = mission_findings((MISSIONS / "AX713.py").read_text(), rule="AX713")
    assert finding.subjects == ("LAND", "FOLLOW_OBJECT_IMAGE")
    land = next(a for a in activations("AX713.py") if a.behavior == "LAND")
    # FOLLOW_OBJECT_IMAGE keeps commanding the vehicle: LAND cannot descend.
    assert land.end_code == "WRONG_PROGRESS"


# -- paths: branches and loops -----------------------------------------------------------
def test_a_finding_on_one_branch_only_names_that_branch() -> None:
    [finding] = mission_findings(
        """\
        import executive_engine_api as api


        def runMission():
            seen, _ = api.consultBelief('visual_marker(?X)')
            if seen:
                api.executeBehavior('TAKE_OFF')
            api.executeBehavior('GO_TO_POINT', coordinates=[1, 0, 1])
        """,
        rule="AX711",
    )
    assert [(s.line, s.action) for s in finding.path] == [(6, "else"), (8, "execute")]
    assert "(path: 6: else; 8: execute GO_TO_POINT)" in finding.message


def test_loops_reach_a_fixed_point_and_report_through_the_iteration() -> None:
    found = mission_findings(
        """\
        import executive_engine_api as api


        def runMission():
            api.executeBehavior('TAKE_OFF')
            while api.trueBelief('battery_level(self, HIGH)'):
                api.activateBehavior('PAY_ATTENTION_TO_VISUAL_MARKERS')
                api.activateBehavior('GO_TO_POINT', coordinates=[1, 0, 1])
                api.executeBehavior('ROTATE', angle=90)
                api.inhibitBehavior('GO_TO_POINT')
            api.executeBehavior('LAND')
        """
    )
    rules = {f.rule for f in found}
    assert "AX715" not in rules  # the loop converged
    [inhibit] = [f for f in found if f.rule == "AX709"]
    assert inhibit.line == 10
    assert any(s.action == "loop #1" for s in inhibit.path)
    [left] = [f for f in found if f.rule == "AX712"]
    assert left.line == 7  # activated in the loop, never inhibited


def test_a_call_inside_an_if_expression_on_a_result_keeps_both_ways() -> None:
    found = mission_findings(
        """\
        import executive_engine_api as api


        def runMission():
            if api.executeBehavior('TAKE_OFF') != 'GOAL_ACHIEVED':
                return
            api.activateBehavior('PAY_ATTENTION_TO_VISUAL_MARKERS')
            api.executeBehavior('LAND')
        """
    )
    [left] = [f for f in found if f.rule == "AX712"]
    assert [s.action for s in left.path] == ["execute", "else", "activate", "execute"]


# -- the declarations the abstract run reads agree with the behaviors' own checks -------
@pytest.mark.parametrize("name", sorted(STANDARD_LIBRARY))
def test_declared_situation_agrees_with_check_situation(name: str) -> None:
    cls = STANDARD_LIBRARY[name]
    catalog = read_catalog(DEFAULT_CATALOG)
    if name not in catalog.behaviors:
        pytest.skip(f"{name} is not in the default catalog")
    verdicts = {}
    for flying in (False, True):
        state = VehicleState(
            (0.0, 0.0, 2.0 if flying else 0.0), (0, 0, 0), 0.0, 1.0, flying, flying
        )
        executive = Executive(catalog, vehicle=NullVehicle(state), library=STANDARD_LIBRARY)
        verdicts[flying] = executive.behaviors[name].situation().ok
    if cls.needs is FlightState.FLYING:
        assert verdicts[False] is False
    elif cls.needs is FlightState.LANDED:
        assert verdicts[True] is False
    else:
        assert verdicts == {False: True, True: True}
    assert cls.leaves in (None, FlightState.FLYING, FlightState.LANDED)


# -- hostile nesting (Python's parser gives up): one line, exit 2 ------------------------
DEEP = {
    "binop": "def runMission():\n    x = " + "1+" * 5000 + "1\n",
    "unary": "def runMission():\n    x = " + "-" * 5000 + "1\n",
    "attributes": "x = a" + ".b" * 5000 + "\n",
    "calls": "x = f" + "()" * 5000 + "\n",
    "not": "x = " + "not " * 5000 + "1\n",
    "lambdas": "x = " + "lambda: " * 5000 + "1\n",
    "ternaries": "x = " + "1 if 1 else " * 5000 + "1\n",
}


@pytest.mark.parametrize("kind", sorted(DEEP))
def test_a_mission_nested_5000_deep_is_one_line_and_exit_2(tmp_path: Path, kind: str) -> None:
    mission = tmp_path / f"{kind}.py"
    mission.write_text(DEEP[kind], encoding="utf-8")
    result = runner.invoke(app, ["verify", str(DEFAULT_CATALOG), "-m", str(mission)])
    assert result.exit_code == 2
    assert "Traceback" not in result.output and "RecursionError" not in result.output
    [line] = result.stderr.strip().splitlines()
    expected_line = 2 if DEEP[kind].startswith("def") else 1
    assert line.startswith(f"{mission}:{expected_line}:1: error: ")
    assert "nested too deeply" in line or "too many nested" in line
    # The catalog, which could be read, was verified.
    assert result.stdout.strip().endswith("1 input could not be read")


def test_deep_but_parsable_expressions_stay_within_the_folder_bounds() -> None:
    text = "import executive_engine_api as api\n\ndef runMission():\n"
    text += "    api.executeBehavior('TAKE_OFF' + " + "(''+" * 150 + "''" + ")" * 150 + ")\n"
    script = parse_mission(text, "deep.py")
    [call] = script.calls
    assert call.behavior is None  # too deep to fold: counted as not checked
    with pytest.raises(MissionError):
        parse_mission("x = " + "(" * 300 + ")" * 300, "parens.py")


def test_a_raise_in_a_helper_ends_the_mission_on_that_path() -> None:
    found = mission_findings(
        """\
        import executive_engine_api as api


        def check(ok):
            if not ok:
                raise RuntimeError('abort')


        def runMission():
            api.activateBehavior('PAY_ATTENTION_TO_VISUAL_MARKERS')
            ok, _ = api.consultBelief('ready(self)')
            check(ok)
            api.executeBehavior('GO_TO_POINT', coordinates=[1, 0, 1])
        """
    )
    # The aborted path reaches neither GO_TO_POINT nor the end: the findings come from
    # the path where the helper returns (its `else`, line 5).
    expected = [(10, "activate"), (5, "else"), (13, "execute")]
    [flight] = [f for f in found if f.rule == "AX711"]
    assert [(s.line, s.action) for s in flight.path] == expected
    [left] = [f for f in found if f.rule == "AX712"]
    assert [(s.line, s.action) for s in left.path] == expected


def test_folding_never_builds_huge_constants() -> None:
    script = parse_mission(
        "import executive_engine_api as api\n\ndef runMission():\n"
        "    name = 'X' * 10**9\n    api.executeBehavior(name)\n"
        "    api.executeBehavior(['A'] * 100000)\n",
        "huge.py",
    )
    assert [c.behavior for c in script.calls] == [None, None]
