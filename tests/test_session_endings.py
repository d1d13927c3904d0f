"""How a session ends: the mission's own endings (sys.exit, KeyboardInterrupt, an
exception at its own line), the simulated time limit, and a vehicle lost to a fault.

Each is the mission's outcome, reported with the summary and exit code 1; none is
aeroexec's own exit. The recording says why the session ended (`aeroexec_end`).
"""

from __future__ import annotations

import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.behaviors import STANDARD_LIBRARY
from aeroexec.catalog import DEFAULT_CATALOG, load_catalog
from aeroexec.cli import app
from aeroexec.executive import EventCode, Executive
from aeroexec.mission.script import Ending
from aeroexec.mission.session import DEFAULT_MAX_SIM_TIME_S, SessionConfig, simulate
from aeroexec.recording import open_recording
from aeroexec.vehicles.base import Vec3, VehicleState
from aeroexec.vehicles.null import NullVehicle

HEADER = "import sys\nimport executive_engine_api as api\n\n"
runner = CliRunner()


def mission(tmp_path: Path, body: str, name: str = "m.py") -> Path:
    path = tmp_path / name
    path.write_text(HEADER + body, encoding="utf-8")
    return path


def end_record(path: Path) -> dict[str, str]:
    return open_recording(path).metadata["aeroexec_end"]


def test_sys_exit_in_a_mission_is_its_failure_not_aeroexecs_exit(tmp_path: Path) -> None:
    path = mission(
        tmp_path, "def runMission():\n    api.executeBehavior('TAKE_OFF')\n    sys.exit(7)\n"
    )
    record = tmp_path / "out.mcap"
    result = subprocess.run(
        [sys.executable, "-m", "aeroexec", "run", str(path), "-o", str(record)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 1, result.stderr
    assert "1 activations: 1 GOAL_ACHIEVED" in result.stdout  # the summary is printed
    assert result.stderr.strip() == f"{path}:6: mission failed: the mission called sys.exit(7)"
    assert end_record(record)["reason"] == "exited"
    assert open_recording(record).complete


def test_sys_exit_0_is_a_mission_that_returned(tmp_path: Path) -> None:
    path = mission(tmp_path, "def runMission():\n    sys.exit(0)\n")
    result = runner.invoke(app, ["run", str(path), "-q"])
    assert result.exit_code == 0, result.output


def test_a_keyboard_interrupt_the_mission_raises_is_its_failure(tmp_path: Path) -> None:
    path = mission(tmp_path, "def runMission():\n    raise KeyboardInterrupt\n")
    result = runner.invoke(app, ["run", str(path), "-q"])
    assert result.exit_code == 1  # not 130: no signal arrived
    assert "0 activations" in result.output
    assert f"{path}:5: mission failed: KeyboardInterrupt" in result.output


def test_an_exception_is_reported_at_the_missions_innermost_line(tmp_path: Path) -> None:
    body = (
        "def check(level):\n"
        "    if level < 50:\n"
        "        raise ValueError(f'battery at {level} %')\n\n"
        "def runMission():\n"
        "    check(12)\n"
    )
    path = mission(tmp_path, body)
    result = runner.invoke(app, ["run", str(path), "-q"])
    assert result.exit_code == 1
    assert f"{path}:6: mission failed: ValueError: battery at 12 %" in result.output
    assert "Traceback" not in result.output


def test_a_mission_nested_5000_deep_is_an_input_error(tmp_path: Path) -> None:
    path = tmp_path / "deep.py"
    path.write_text("x = " + "-" * 5000 + "1\n", encoding="utf-8")
    result = runner.invoke(app, ["run", str(path)])
    assert result.exit_code == 2
    assert result.output.strip() == f"{path}: error: invalid Python: nested too deeply to compile"


FOREVER = (
    "def runMission():\n"
    "    api.executeBehavior('TAKE_OFF')\n"
    "    while True:\n"
    "        try:\n"
    "            api.executeBehavior('WAIT', duration=7)\n"
    "        except Exception:\n"  # must not swallow the limit
    "            pass\n"
)


def test_max_sim_time_stops_a_mission_that_never_ends(tmp_path: Path) -> None:
    path = mission(tmp_path, FOREVER)
    record = tmp_path / "forever.mcap"
    result = runner.invoke(app, ["run", str(path), "-q", "--max-sim-time", "60", "-o", str(record)])
    assert result.exit_code == 1
    assert "60.0 s simulated" in result.output
    assert (
        f"{path}:8: mission stopped: the simulated time limit of 60 s was reached "
        "(--max-sim-time)" in result.output
    )
    end = end_record(record)
    assert end["reason"] == "max_sim_time"
    assert end["time_ns"] == str(60 * 10**9)
    rec = open_recording(record)
    assert rec.complete
    last_state = max(m.log_time_ns for m in rec.messages())
    assert last_state == 60 * 10**9  # not a tick further


def test_the_default_limit_is_one_simulated_day() -> None:
    assert DEFAULT_MAX_SIM_TIME_S == 86400.0
    assert SessionConfig(mission="m.py").max_sim_time_s == DEFAULT_MAX_SIM_TIME_S


def test_a_mission_that_returns_is_recorded_as_such(tmp_path: Path) -> None:
    path = mission(tmp_path, "def runMission():\n    api.executeBehavior('TAKE_OFF')\n")
    result = simulate(SessionConfig(mission=path, record=tmp_path / "ok.mcap"))
    assert result.outcome.returned and result.outcome.ending is Ending.RETURNED
    end = end_record(tmp_path / "ok.mcap")
    assert end["reason"] == "returned" and "vehicle_fault" not in end


# -- vehicle faults --------------------------------------------------------------------
LOW_BATTERY_WORLD = "name: low\nseed: 0\nbattery:\n  initial: 20\n"
HOVER_LONG = (
    "def runMission():\n"
    "    api.executeBehavior('TAKE_OFF')\n"
    "    print(api.executeBehavior('KEEP_HOVERING', duration=1000))\n"
)


def test_keep_hovering_fails_when_the_battery_dies_and_run_says_so(tmp_path: Path) -> None:
    world = tmp_path / "low.yaml"
    world.write_text(LOW_BATTERY_WORLD, encoding="utf-8")
    path = mission(tmp_path, HOVER_LONG)
    record = tmp_path / "h.mcap"
    result = runner.invoke(app, ["run", str(path), "--world", str(world), "-o", str(record)])
    assert result.exit_code == 1, result.output
    out = result.output
    assert "KEEP_HOVERING PROCESS_FAILURE after 237.8 s (vehicle fault: battery_empty)" in out
    assert "[  240.1 s] FAULT    vehicle: battery_empty" in out
    assert 'GOAL_ACHIEVED "hovered' not in out and "hovered 1000 s" not in out
    assert "fault battery_empty" in out  # the summary line
    assert "mission failed: the vehicle was lost: fault battery_empty at 240.1 s" in out
    assert end_record(record)["vehicle_fault"] == "battery_empty"


class FaultyVehicle(NullVehicle):
    """Holds still wherever the test puts it, reporting `fault`; sees an object."""

    def __init__(self, state: VehicleState) -> None:
        super().__init__(state)
        self.fault = ""

    def state(self) -> VehicleState:
        return replace(super().state(), fault=self.fault)

    def visible_object(self) -> Vec3 | None:
        return (3.0, 0.0, 1.0)


FLYING = VehicleState((0.0, 0.0, 1.5), (0.0, 0.0, 0.0), 0.0, 0.9, True, True)
GROUNDED = VehicleState((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0, 0.9, False, False)
LINK = {"link_lost", "mode_changed"}
MOTION = LINK | {"battery_empty"}
#: The faults that make each standard behavior's goal impossible (this test's own table).
IMPOSSIBLE: dict[str, tuple[set[str], dict[str, object], VehicleState]] = {
    "TAKE_OFF": (MOTION, {}, GROUNDED),
    "LAND": (LINK, {}, FLYING),  # an empty battery lands the vehicle: the goal holds
    "GO_TO_POINT": (MOTION, {"COORDINATES": [5, 5, 2]}, FLYING),
    "ROTATE": (MOTION, {"ANGLE": 90}, FLYING),
    "START_MOVING": (MOTION, {"SPEED": 1, "DIRECTION": "FORWARD"}, FLYING),
    "FOLLOW_OBJECT_IMAGE": (MOTION, {}, FLYING),
    "FLIP": (MOTION, {"DIRECTION": "BACK"}, FLYING),
    "KEEP_HOVERING": (MOTION | {"stuck_motor"}, {"DURATION": 100}, FLYING),
    "START_HOVERING": (MOTION | {"stuck_motor"}, {}, FLYING),
    "WAIT": (set(), {"DURATION": 100}, FLYING),
    "BROADCAST_MESSAGE": (set(), {"TEXT": "hello"}, FLYING),
    "PAY_ATTENTION_TO_VISUAL_MARKERS": (set(), {}, FLYING),
}
FAULTS = ["link_lost", "mode_changed", "battery_empty", "stuck_motor"]


def test_the_table_covers_the_standard_library() -> None:
    assert set(IMPOSSIBLE) | {"PAY_ATTENTION"} == set(STANDARD_LIBRARY)


@pytest.mark.parametrize("behavior", list(IMPOSSIBLE))
@pytest.mark.parametrize("fault", FAULTS)
def test_each_standard_behavior_ends_on_the_faults_that_defeat_it(
    behavior: str, fault: str
) -> None:
    failing, arguments, state = IMPOSSIBLE[behavior]
    vehicle = FaultyVehicle(state)
    ex = Executive(load_catalog(DEFAULT_CATALOG), vehicle=vehicle, library=STANDARD_LIBRARY)
    result = ex.activate_behavior(behavior, arguments)
    assert result.ok, result.error
    vehicle.fault = fault
    ex.step()
    ended = [(e.code, e.detail) for e in ex.events]
    if fault in failing:
        assert ended == [(EventCode.PROCESS_FAILURE, f"vehicle fault: {fault}")]
    else:
        # Goes on, or ends by its own measure -- and says the fault if that is a failure.
        assert all(
            code is EventCode.GOAL_ACHIEVED or f"vehicle fault: {fault}" in detail
            for code, detail in ended
        ), ended
        assert (EventCode.PROCESS_FAILURE, f"vehicle fault: {fault}") not in ended
