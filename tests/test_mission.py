"""The mission API, the script runner, simulated sessions and `aeroexec run`."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.catalog import THESIS_CATALOG, load_catalog
from aeroexec.cli import app
from aeroexec.errors import MissionError
from aeroexec.executive import Executive, GenericBehavior, MemoryObserver
from aeroexec.executive.messages import ServiceCallRecord
from aeroexec.mission import APPENDIX_C, MissionAPI, SessionConfig, load_mission, simulate
from aeroexec.mission.script import compile_mission, run_script
from aeroexec.vehicles.null import NullVehicle

runner = CliRunner()


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


MISSION_HEADER = "import executive_engine_api as api\n\n"


# -- the thesis' Appendix C ---------------------------------------------------------------
def test_appendix_c_runs_to_the_end_in_simulation() -> None:
    result = simulate(SessionConfig(mission=APPENDIX_C))
    assert result.outcome.returned and result.outcome.value is True
    rows = [(a.behavior, a.result) for a in result.activations]
    assert rows == [
        ("TAKE_OFF", "GOAL_ACHIEVED"),
        ("PAY_ATTENTION_TO_VISUAL_MARKERS", "INTERRUPTED"),  # inhibited by the mission
        ("GO_TO_POINT", "GOAL_ACHIEVED"),
        ("GO_TO_POINT", "GOAL_ACHIEVED"),
        ("ROTATE", "GOAL_ACHIEVED"),
        ("GO_TO_POINT", "GOAL_ACHIEVED"),
        ("LAND", "GOAL_ACHIEVED"),
    ]
    assert not result.final_state.flying
    assert result.final_state.altitude == pytest.approx(0.0, abs=1e-6)


def test_appendix_c_return_home_uses_the_unified_position() -> None:
    """consult_belief's unification feeds the last GO_TO_POINT: it must be the position
    memorized after the relative climb, not the target point."""
    result = simulate(SessionConfig(mission=APPENDIX_C))
    climb, target, home = [a for a in result.activations if a.behavior == "GO_TO_POINT"]
    assert target.arguments == {"coordinates": [3, 5.5, 1.3]}
    x, y, z = home.arguments["coordinates"]
    assert abs(x) < 0.2 and abs(y) < 0.2  # took off from the origin
    assert z > 1.0  # after take-off plus the 0.5 m climb
    assert climb.arguments == {"relative_coordinates": [0, 0, 0.5]}
    # the vehicle went back near the memorized point before landing
    fx, fy, _ = result.final_state.position
    assert abs(fx - x) < 0.3 and abs(fy - y) < 0.3


def test_same_mission_twice_gives_the_same_stream() -> None:
    first, second = MemoryObserver(), MemoryObserver()
    simulate(SessionConfig(mission=APPENDIX_C), observers=[first])
    simulate(SessionConfig(mission=APPENDIX_C), observers=[second])
    assert len(first.records) > 100
    assert first.records == second.records


def test_mission_commands_are_published_before_their_effect() -> None:
    observer = MemoryObserver()
    simulate(SessionConfig(mission=APPENDIX_C), observers=[observer])
    commands = observer.topics("mission/command")
    assert [c["command"] for c in commands][:3] == [
        "execute_behavior",
        "activate_behavior",
        "execute_behavior",
    ]
    # Each names the line of the mission that made it.
    text = APPENDIX_C.read_text(encoding="utf-8").splitlines()
    consult = next(n for n, line in enumerate(text, 1) if "api.consultBelief(" in line)
    query = "position(self, (?X, ?Y, ?Z))"
    assert {"command": "consult_belief", "query": query, "line": consult} in commands
    assert all("api." in text[c["line"] - 1] for c in commands)
    activations = [r for r in observer.calls("activate_behavior") if r.parent_seq is None]
    assert len(activations) == sum(
        c["command"] in ("execute_behavior", "activate_behavior") for c in commands
    )


# -- the API ------------------------------------------------------------------------------
def null_api() -> MissionAPI:
    return MissionAPI(
        Executive(
            load_catalog(THESIS_CATALOG),
            vehicle=NullVehicle(),
            library={},
            stand_in=GenericBehavior,
        )
    )


def test_execute_behavior_of_a_recurrent_behavior_is_refused_at_once() -> None:
    api = null_api()
    with pytest.raises(MissionError) as refused:
        api.execute_behavior("PAY_ATTENTION")
    assert str(refused.value) == (
        "execute_behavior('PAY_ATTENTION'): PAY_ATTENTION is recurrent and would never "
        "return; use activate_behavior and inhibit_behavior"
    )
    assert api.executive.active_behaviors == ()
    assert api.executive.now_s == 0.0
    # A mission in the thesis' spelling is told in its own spelling.
    with pytest.raises(MissionError) as camel:
        api.executeBehavior("PAY_ATTENTION")
    assert str(camel.value) == (
        "executeBehavior('PAY_ATTENTION'): PAY_ATTENTION is recurrent and would never "
        "return; use activateBehavior and inhibitBehavior"
    )
    with pytest.raises(MissionError, match=r"^consultBelief: "):
        api.consultBelief("flying(")
    with pytest.raises(MissionError, match=r"^consult_belief: "):
        api.consult_belief("flying(")


def test_refused_execution_returns_error_and_says_why() -> None:
    api = null_api()
    assert api.executeBehavior("GO_TO_POINT", coordinates=[1, 2]) == "ERROR"
    assert api.lastError() == "GO_TO_POINT: COORDINATES needs 3 numbers in [-100, 100], got 2"
    assert api.execute_behavior("GO_TO_POINT", coordinates=[1, 2, 3]) == "GOAL_ACHIEVED"
    assert api.last_error() == ""


def test_activate_and_inhibit_return_acknowledgements() -> None:
    api = null_api()
    assert api.activateBehavior("PAY_ATTENTION") is True
    assert api.executive.active_behaviors == ("PAY_ATTENTION",)
    assert api.inhibitBehavior("PAY_ATTENTION") is True
    assert api.inhibitBehavior("PAY_ATTENTION") is False
    assert "not active" in api.last_error()
    assert api.activate_behavior("NO_SUCH_BEHAVIOR") is False


def test_beliefs_through_the_api() -> None:
    api = null_api()
    assert api.addBelief("object(self, box)")
    assert api.consultBelief("object(self, ?What)") == (True, {"What": "box"})
    assert api.trueBelief("object(self, box)")
    assert api.removeBelief("object(self, box)")
    assert api.consult_belief("object(self, ?What)") == (False, {})
    with pytest.raises(MissionError, match="consult_belief"):
        api.consult_belief("position(self,, )")


# -- scripts ------------------------------------------------------------------------------
def test_entry_points_other_than_runMission_are_accepted(tmp_path: Path) -> None:
    for entry in ("run_mission", "main"):
        script = compile_mission(MISSION_HEADER + f"def {entry}():\n    return 7\n")
        assert run_script(script, null_api()).value == 7


def test_api_module_is_only_importable_while_the_script_runs() -> None:
    script = compile_mission(MISSION_HEADER + "def main():\n    return api.true_belief('x(y)')\n")
    run_script(script, null_api())
    assert "executive_engine_api" not in sys.modules


def test_script_without_entry_point_is_unusable(tmp_path: Path) -> None:
    script = compile_mission("x = 1\n", "m.py")
    with pytest.raises(MissionError, match="defines none of runMission"):
        run_script(script, null_api())


def test_syntax_error_points_at_line_and_column(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        "bad.py",
        MISSION_HEADER + "def runMission():\n    api.executeBehavior('ROTATE', angle:-90)\n",
    )
    with pytest.raises(MissionError) as info:
        load_mission(path)
    assert info.value.mark is not None
    assert (info.value.mark.line, info.value.mark.column) == (4, 40)  # the ":" of the thesis typo


# -- the CLI ------------------------------------------------------------------------------
def test_run_prints_behaviors_and_summary_and_exits_0() -> None:
    result = runner.invoke(app, ["run", str(APPENDIX_C)])
    assert result.exit_code == 0, result.output
    assert "start    TAKE_OFF" in result.output
    assert "end      LAND GOAL_ACHIEVED" in result.output
    assert "7 activations: 6 GOAL_ACHIEVED, 0 rejected" in result.output
    assert "vehicle landed" in result.output


def test_run_exit_1_when_the_mission_raises(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        "boom.py",
        MISSION_HEADER + "def runMission():\n    api.executeBehavior('TAKE_OFF')\n"
        "    raise RuntimeError('battery sensor disagrees')\n",
    )
    result = subprocess.run(
        [sys.executable, "-m", "aeroexec", "run", str(path)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 1
    # The mission's own line, without --debug.
    expected = f"{path}:5: mission failed: RuntimeError: battery sensor disagrees"
    assert result.stderr.strip() == expected
    assert "Traceback" not in result.stdout + result.stderr
    debug = runner.invoke(app, ["run", str(path), "--debug"])
    assert debug.exit_code == 1
    assert "Traceback" in debug.output


def test_run_exit_1_for_executing_a_recurrent_behavior(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        "rec.py",
        MISSION_HEADER
        + "def runMission():\n    api.executeBehavior('PAY_ATTENTION_TO_VISUAL_MARKERS')\n",
    )
    result = runner.invoke(app, ["run", str(path)])
    assert result.exit_code == 1
    assert (
        "is recurrent and would never return; use activateBehavior and inhibitBehavior"
        in result.stderr
    )


@pytest.mark.parametrize(
    ("files", "args", "expected"),
    [
        ({}, ["missing.py"], "missing.py: error: no such file"),
        ({"bad.py": "def runMission(:\n"}, ["bad.py"], "bad.py:1:16: error: invalid Python"),
        ({"m.py": "x = 1\n"}, ["m.py"], "m.py: error: defines none of"),
        (
            {
                "m.py": "def main():\n    pass\n",
                "c.yaml": "behavior_descriptors: 3\ncapability_descriptors: []\n",
            },
            ["m.py", "--catalog", "c.yaml"],
            "c.yaml:1:23: error:",
        ),
        (
            {"m.py": "def main():\n    pass\n", "w.yaml": "markers: [[1, 2]]\n"},
            ["m.py", "--world", "w.yaml"],
            "w.yaml:1:",
        ),
    ],
)
def test_run_exit_2_for_unreadable_input(
    tmp_path: Path, files: dict[str, str], args: list[str], expected: str
) -> None:
    for name, text in files.items():
        write(tmp_path, name, text)
    result = subprocess.run(
        [sys.executable, "-m", "aeroexec", "run", *args],
        capture_output=True,
        text=True,
        check=False,
        cwd=tmp_path,
    )
    assert result.returncode == 2, result.stdout + result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(expected), lines
    assert "Traceback" not in result.stdout + result.stderr


def test_activity_sees_only_mission_activations() -> None:
    observer = MemoryObserver()
    result = simulate(SessionConfig(mission=APPENDIX_C), observers=[observer])
    roots = [
        r
        for r in observer.records
        if isinstance(r, ServiceCallRecord) and r.service == "activate_behavior"
    ]
    assert len(roots) == len(result.activations)
