"""When the autopilot says no, against `MavSim` (fast): arming refused (ArduCopter's
battery check, `BATT_ARM_VOLT`) makes `fly` exit 1 with the autopilot's own reason on the
console; the failsafe preflight refuses a vehicle whose GCS failsafe is off before
anything is armed; and closed-loop replay of a flight whose commands were refused (or
sent during a link loss) gives the flight again, 0 differences. The same refusals are
flown on ArduCopter SITL in test_sitl_flights.py."""

from __future__ import annotations

from pathlib import Path

from live_helpers import free_udp_port, mavsim_thread, write_mission
from typer.testing import CliRunner

from aeroexec.cli import app

TAKE_OFF_AND_LAND = "    return [api.executeBehavior('TAKE_OFF'), api.executeBehavior('LAND')]\n"
ARM_REFUSED = "Arm: Battery 1 below minimum arming voltage"


def fly_cli(mission: Path, port: int, *extra: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(
        app, ["fly", str(mission), "--connect", f"udpin:127.0.0.1:{port}", *extra]
    )
    return result.exit_code, result.stdout, result.stderr


# -- 1. nothing flew: exit 1, with the autopilot's reason -----------------------------------


def test_arming_refused_exits_1_with_the_autopilots_reason(tmp_path: Path) -> None:
    port = free_udp_port()
    mission = write_mission(tmp_path, TAKE_OFF_AND_LAND)
    with mavsim_thread(f"udpout:127.0.0.1:{port}", params=(("BATT_ARM_VOLT", 20.0),)) as sim:
        code, out, err = fly_cli(mission, port, "-o", str(tmp_path / "f.mcap"))
        final = sim.stats()["final"]
    assert code == 1, out + err
    assert not final["armed"] and not final["flying"]
    # On the console as the autopilot said it, and in the behavior's ending ...
    assert f"autopilot: {ARM_REFUSED}" in out
    assert "end      TAKE_OFF PROCESS_FAILURE after 0.0 s (" in out
    assert "after -0" not in out
    # ... and in the last word on stderr: why the mission failed.
    assert (
        "aeroexec fly: mission failed: TAKE_OFF ended PROCESS_FAILURE: on_start failed: "
        "VehicleCommandError: MAV_CMD_COMPONENT_ARM_DISARM refused: FAILED "
        f"(autopilot: {ARM_REFUSED})"
    ) in err


def test_a_refusal_without_a_statustext_still_exits_1(tmp_path: Path) -> None:
    port = free_udp_port()
    mission = write_mission(tmp_path, TAKE_OFF_AND_LAND)
    with mavsim_thread(f"udpout:127.0.0.1:{port}", refuse=(400,)):
        code, _, err = fly_cli(mission, port)
    assert code == 1
    assert err.strip().splitlines()[0] == (
        "aeroexec fly: mission failed: TAKE_OFF ended PROCESS_FAILURE: on_start failed: "
        "VehicleCommandError: MAV_CMD_COMPONENT_ARM_DISARM refused: TEMPORARILY_REJECTED"
    )
