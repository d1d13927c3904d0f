"""Task catalogs (Aerostack 4.x, 2020-2021): loading, the defects of the real ones, and
the model of the 2021 coordinator that witnesses are built on.

The CBC coordinator's own test catalogs (cvar-upm/coordinator_cbc
`behavior_coordinator/src/test/`) are the specification: each was written to show one
defect the coordinator's loader reports (`catalog.cpp`), and the verifier must find
exactly that one at its place. The coordinator's own test (`behavior_coordinator_test.cpp`)
starts TAKE_OFF, then FOLLOW_PATH, on behavior_catalog.yaml and expects both accepted;
the model must agree.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.catalog.formats import parse_any_catalog, read_any_catalog
from aeroexec.catalog.tasks import ExecutionGoal, ParameterKind, TaskCatalog
from aeroexec.cli import app
from aeroexec.errors import CatalogError
from aeroexec.verifier import verify
from aeroexec.verifier.engine import check_task_catalog
from aeroexec.verifier.findings import Finding
from aeroexec.verifier.task_model import IDLE, TaskModel

REAL = Path(__file__).resolve().parent / "fixtures" / "verifier_catalogs"
CBC = "cvar-upm+coordinator_cbc__behavior_coordinator_src_test_"
CBC_GOOD = REAL / f"{CBC}behavior_catalog__4edaaf8.yaml"
CBC_BAD = REAL / f"{CBC}bad_behavior_catalog__4edaaf8.yaml"
CBC_IMPOSSIBLE = REAL / f"{CBC}behavior_catalog_impossible__4edaaf8.yaml"
CBC_MISSING = REAL / f"{CBC}behavior_catalog_missing_task__4edaaf8.yaml"
PIXHAWK = (
    REAL / "aerostack+basic_mission_pixhawk_gazebo__configs_mission_behavior_catalog__488ed5c.yaml"
)
BEBOP = REAL / "aerostack-lab+basic_mission_bebop__configs_mission_behavior_catalog__9083d30.yaml"
AEROSTACK_2020 = REAL / "cvar-upm+aerostack__config_mission_behavior_catalog__abbd8b2.yaml"
TASK_CATALOGS = [CBC_GOOD, CBC_BAD, CBC_IMPOSSIBLE, CBC_MISSING, PIXHAWK, BEBOP, AEROSTACK_2020]

runner = CliRunner()


def task_catalog(path: Path) -> TaskCatalog:
    catalog = read_any_catalog(path)
    assert isinstance(catalog, TaskCatalog)
    return catalog


def findings(path: Path, rule: str | None = None) -> list[Finding]:
    found = check_task_catalog(task_catalog(path))
    return sorted(
        (f for f in found if rule is None or f.rule == rule), key=lambda f: (f.line, f.column)
    )


def places(path: Path, rule: str) -> list[tuple[int, int]]:
    return [(f.line, f.column) for f in findings(path, rule)]


# -- every real task catalog is verified, never refused ------------------------------------
@pytest.mark.parametrize("path", TASK_CATALOGS, ids=lambda p: p.name[:50])
def test_real_task_catalog_is_verified_with_exit_0_or_1(path: Path) -> None:
    result = runner.invoke(app, ["verify", str(path)])
    assert result.exit_code in (0, 1), result.output
    assert result.stderr == ""
    assert " in 1 file" in result.stdout


def test_the_bebop_catalog_that_flew_is_clean() -> None:
    result = runner.invoke(app, ["verify", str(BEBOP), "--strict"])
    assert result.exit_code == 0, result.stdout


def test_model_of_the_real_catalogs() -> None:
    good = task_catalog(CBC_GOOD)
    assert good.dialect == "cbc-2021"
    assert len(good.behaviors) == 26
    assert good.performers("FOLLOW_PATH") == (
        "FOLLOW_PATH_WITH_MPC_CONTROL",
        "FOLLOW_PATH_WITH_PID_CONTROL",
    )
    assert good.behavior("FOLLOW_PATH_WITH_PID_CONTROL").suitability == 90
    assert good.behavior("WAIT").suitability == 100  # default_values behaviors
    hover = good.tasks["HOVER"]
    assert (hover.execution_goal, hover.start_on_request, hover.reactive_start) == (
        ExecutionGoal.KEEP_RUNNING,
        False,
        False,
    )
    assert good.tasks["ROTATE"].timeout == 30 and good.tasks["WAIT"].timeout == 15
    assert [(p.name, p.kind, p.minimum, p.maximum) for p in good.tasks["WAIT"].parameters] == [
        ("duration", ParameterKind.RANGE, 0, 1000)
    ]
    assert good.tasks["MOVE"].parameters[1].symbols == ("FORWARD", "BACKWARD", "LEFT", "RIGHT")
    assert good.exclusive_with("PID_MOTION_CONTROL") == {"MPC_MOTION_CONTROL"}
    requirement = good.behavior("QUADROTOR_MPC_MOTION_CONTROL").requires[0]
    assert (requirement.task, requirement.minimum_performance) == ("SELF_LOCALIZE", 80)

    # The 2020 vocabulary means the same: recurrent + default + automatic_activation.
    old = task_catalog(AEROSTACK_2020)
    assert old.dialect == "aerostack-4.0-2020"
    hover = old.tasks["HOVER"]
    assert (hover.execution_goal, hover.reactive_start) == (ExecutionGoal.KEEP_RUNNING, True)
    assert old.tasks["PID_MOTION_CONTROL"].start_on_request is False  # automatic_activation
    assert old.tasks["TAKE_OFF"].start_on_request is True  # default_values
    assert old.behavior("ESTIMATE_POSITION_WITH_LINEAR_SPEED").suitability == 80  # efficacy


# -- the coordinator's own test catalogs: one defect each, where it is ---------------------
def test_bad_behavior_catalog_has_a_behavior_without_a_task() -> None:
    [missing] = findings(CBC_BAD, "AX801")
    assert (missing.line, missing.column) == (65, 3)
    assert "'The behavior: LAND has no task defined'" in missing.message
    [orphan] = findings(CBC_BAD, "AX811")
    assert (orphan.line, orphan.subjects) == (202, ("LAND",))
    assert orphan.witness is not None and orphan.witness.to_list() == [
        {"start_task": "LAND", "arguments": {}}
    ]


def test_impossible_catalog_has_conflicting_constraints() -> None:
    [conflict] = findings(CBC_IMPOSSIBLE, "AX814")
    assert (conflict.line, conflict.column) == (147, 11)
    assert (
        "'Conflicting constraints: requires(QUADROTOR_PID_MOTION_CONTROL(PID_MOTION_CONTROL),"
        "MPC_MOTION_CONTROL,0.000000) and incompatible(PID_MOTION_CONTROL,MPC_MOTION_CONTROL)'"
    ) in conflict.message
    [siblings] = findings(CBC_IMPOSSIBLE, "AX815")
    assert siblings.subjects == (
        "QUADROTOR_PID_MOTION_CONTROL",
        "THRUST_CONTROL",
        "MPC_MOTION_CONTROL",
    )
    never = {f.subjects[0]: f for f in findings(CBC_IMPOSSIBLE, "AX816")}
    assert set(never) == {"MOVE", "PID_MOTION_CONTROL"}  # HOVER, ROTATE... go through MPC
    assert never["MOVE"].line == 220


def test_missing_task_catalog_requires_an_undeclared_task() -> None:
    [missing] = findings(CBC_MISSING, "AX812")
    assert (missing.line, missing.column) == (111, 11)
    assert "'The required task: SELF_LOCALIZE_NON_EXISTENT is not declared'" in missing.message
    assert "(did you mean 'SELF_LOCALIZE'?)" in missing.message
    assert [f.subjects[0] for f in findings(CBC_MISSING, "AX816")] == ["MPC_MOTION_CONTROL"]


def test_the_good_test_catalog_has_only_the_misindented_parameter() -> None:
    errors_and_warnings = [f for f in findings(CBC_GOOD) if f.severity.value != "info"]
    assert [(f.rule, f.line, f.column) for f in errors_and_warnings] == [("AX803", 294, 3)]
    assert "under '- parameter: options' (line 293)" in errors_and_warnings[0].message
    assert task_catalog(CBC_GOOD).tasks["REQUEST_OPERATOR_ASSISTANCE"].parameters[-1].kind is (
        ParameterKind.UNSPECIFIED
    )


def test_pixhawk_catalog_duplicates_tasks_and_declares_tasks_nobody_performs() -> None:
    assert places(PIXHAWK, "AX805") == [(144, 3), (146, 3)]
    assert [f.subjects[0] for f in findings(PIXHAWK, "AX811")] == [
        "HOVER",
        "MOVE_AT_SPEED",
        "PID_MOTION_CONTROL",
        "THRUST_CONTROL",
    ]
    [on_request] = findings(PIXHAWK, "AX818")
    assert on_request.subjects == ("SEND_PATH", "FOLLOW_PATH")
    assert on_request.witness is not None
    assert on_request.witness.describe() == (
        "start task SEND_PATH: the start of SEND_PATH is rejected (replayed on the model of "
        "the 2021 task coordinator; `aeroexec run` runs behavior catalogs only)"
    )


# -- the model of the 2021 coordinator ------------------------------------------------------
def test_model_accepts_what_the_coordinators_own_test_expects() -> None:
    model = TaskModel(task_catalog(CBC_GOOD))
    took_off = model.start_task(IDLE, "TAKE_OFF")
    assert took_off.accepted
    running = {t: b for t, b, _ in took_off.after}
    assert running["TAKE_OFF"] == "TAKE_OFF"
    assert running["THRUST_CONTROL"] == "QUADROTOR_PID_THRUST_CONTROL"
    assert "SELF_LOCALIZE" in running  # required by THRUST_CONTROL's behavior
    following = model.start_task(took_off.after, "FOLLOW_PATH")
    assert following.accepted
    running = {t: b for t, b, _ in following.after}
    assert running["FOLLOW_PATH"] == "FOLLOW_PATH_WITH_PID_CONTROL"  # 90 % beats 80 %
    assert "TAKE_OFF" not in running  # mutually exclusive: preempted


def test_model_keeps_a_higher_priority_task_and_blocks_what_excludes_it() -> None:
    model = TaskModel(task_catalog(CBC_GOOD))
    urgent = model.start_task(IDLE, "HOVER", priority=3)
    assert urgent.accepted
    blocked = model.start_task(urgent.after, "ROTATE", priority=2)
    assert blocked.accepted is False
    assert "mutually exclusive" in blocked.reason


def test_model_does_not_start_on_request_tasks_for_a_requirement() -> None:
    catalog = task_catalog(PIXHAWK)
    strict = TaskModel(catalog)
    refused = strict.start_task(IDLE, "SEND_PATH")
    assert refused.accepted is False
    assert "FOLLOW_PATH starts only on request" in refused.reason
    requested = strict.start_task(IDLE, "FOLLOW_PATH")
    assert requested.accepted
    assert strict.start_task(requested.after, "SEND_PATH").accepted
    assert TaskModel(catalog, on_request_blocks=False).start_task(IDLE, "SEND_PATH").accepted


# -- loading: the coordinator's way of reading values --------------------------------------
TINY = """\
default_values:
- tasks:
  - execution_goal: achieve_goal
    start_on_request: TRUE
    reactive_start: FALSE
    timeout: 15
behaviors:
- behavior: GO
  task: GO
tasks:
- task: GO
  start_on_request: {flag}
"""


@pytest.mark.parametrize(
    ("flag", "value", "warned"),
    [("TRUE", True, False), ("FALSE", False, False), ("true", False, True), ("yes", False, True)],
)
def test_booleans_are_the_text_true(flag: str, value: bool, warned: bool) -> None:
    catalog = parse_any_catalog(TINY.format(flag=flag))
    assert isinstance(catalog, TaskCatalog)
    assert catalog.tasks["GO"].start_on_request is value
    assert any(d.code == "AX808" for d in catalog.diagnostics) is warned


def test_run_refuses_a_task_catalog_naming_the_format(tmp_path: Path) -> None:
    mission = Path(__file__).resolve().parent.parent / "missions" / "appendix_c.py"
    result = runner.invoke(app, ["run", str(mission), "-c", str(BEBOP)])
    assert result.exit_code == 2
    [line] = result.stderr.strip().splitlines()
    assert line.startswith(f"{BEBOP}:48:1: error: this is an Aerostack 4.x task-based catalog")
    assert "`aeroexec verify` checks task catalogs" in line


def test_task_catalog_with_a_broken_section_is_still_verified() -> None:
    text = "behaviors: 5\ntasks:\n- task: X\n"
    catalog = parse_any_catalog(text, "t.yaml")
    assert isinstance(catalog, TaskCatalog)
    assert [d.code for d in catalog.diagnostics if d.severity.value == "error"] == ["AX804"]
    report = verify([catalog])
    assert report.exit_code() == 1


def test_unreadable_yaml_is_still_an_input_error() -> None:
    with pytest.raises(CatalogError):
        parse_any_catalog("behaviors: [\n", "t.yaml")
