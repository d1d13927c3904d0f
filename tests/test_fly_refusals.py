"""When the autopilot says no, against `MavSim` (fast): arming refused (ArduCopter's
battery check, `BATT_ARM_VOLT`) makes `fly` exit 1 with the autopilot's own reason on the
console; the failsafe preflight refuses a vehicle whose GCS failsafe is off before
anything is armed; and closed-loop replay of a flight whose commands were refused (or
sent during a link loss) gives the flight again, 0 differences. The same refusals are
flown on ArduCopter SITL in test_sitl_flights.py."""

from __future__ import annotations

from pathlib import Path

from live_helpers import free_udp_port, mavsim_thread, write_mission
from pymavlink.dialects.v20 import ardupilotmega as mavlink
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.mission.live import FlightConfig, fly
from aeroexec.recording import open_recording
from aeroexec.recording.reader import RecordedTopic
from aeroexec.replay.engine import Mode, ReplayOptions, replay_recording
from aeroexec.replay.refusals import recorded_refusals
from aeroexec.vehicles.mavlink.preflight import FAILSAFE_PARAMETERS, preflight
from aeroexec.vehicles.mavlink.vehicle import MavlinkConfig, MavlinkVehicle

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


# -- 2. the failsafe preflight ----------------------------------------------------------------


def test_a_gcs_failsafe_that_is_off_is_refused_before_arming(tmp_path: Path) -> None:
    port = free_udp_port()
    record = tmp_path / "f.mcap"
    mission = write_mission(tmp_path, TAKE_OFF_AND_LAND)
    with mavsim_thread(f"udpout:127.0.0.1:{port}", params=(("FS_GCS_ENABLE", 0.0),)) as sim:
        code, out, err = fly_cli(mission, port, "-o", str(record))
        commands = [c["command"] for c in sim.stats()["commands"]]
    assert code == 2, out + err
    assert "preflight: GCS failsafe off; battery failsafes low none, critical none" in out
    assert err.strip() == (
        "aeroexec fly: error: the autopilot's GCS failsafe is off (FS_GCS_ENABLE=0): if fly "
        "stops or its link is lost for good, the vehicle hovers in GUIDED until its battery "
        "is empty; set FS_GCS_ENABLE=5 (land) or 1 (RTL) on the autopilot, or pass "
        "--allow-no-gcs-failsafe; nothing was armed"
    )
    # Nothing but the stream requests went to the autopilot: no mode, no arming.
    assert set(commands) == {"MAV_CMD_SET_MESSAGE_INTERVAL"}
    assert not record.exists()


def test_allow_no_gcs_failsafe_flies_with_one_warning(tmp_path: Path) -> None:
    port = free_udp_port()
    mission = write_mission(tmp_path, TAKE_OFF_AND_LAND)
    with mavsim_thread(f"udpout:127.0.0.1:{port}", params=(("FS_GCS_ENABLE", 0.0),)) as sim:
        code, out, err = fly_cli(mission, port, "--allow-no-gcs-failsafe")
        final = sim.stats()["final"]
    assert code == 0, out + err
    warnings = [line for line in err.splitlines() if "FS_GCS_ENABLE=0" in line]
    assert len(warnings) == 1 and warnings[0].startswith("warning: the autopilot's GCS failsafe")
    assert "2 activations: 2 GOAL_ACHIEVED" in out
    assert final["mode"] == "LAND" and not final["armed"]


def test_the_failsafes_are_read_with_the_parameter_protocol_and_reported(
    tmp_path: Path,
) -> None:
    port = free_udp_port()
    mission = write_mission(tmp_path, TAKE_OFF_AND_LAND)
    params = (("FS_GCS_ENABLE", 5.0), ("FS_GCS_TIMEOUT", 3.0), ("BATT_FS_LOW_ACT", 2.0))
    params += (("BATT_ARM_VOLT", 20.0),)
    record = tmp_path / "f.mcap"
    with mavsim_thread(f"udpout:127.0.0.1:{port}", params=params):
        code, out, _ = fly_cli(mission, port, "-o", str(record))
    assert code == 1  # arming refused: see above
    assert "preflight: GCS failsafe LAND after 3 s; battery failsafes low RTL, critical none" in out
    # The autopilot's own pre-arm verdict (SYS_STATUS), before the mission starts.
    lines = out.splitlines()
    prearm = lines.index("preflight: pre-arm failure: SYS_STATUS unhealthy: PREARM_CHECK")
    assert prearm < next(i for i, line in enumerate(lines) if "start    TAKE_OFF" in line)
    recording = open_recording(record)
    assert recording.metadata["aeroexec"]["failsafe_parameters"] == (
        "FS_GCS_ENABLE=5 FS_GCS_TIMEOUT=3 BATT_FS_LOW_ACT=2 BATT_FS_CRT_ACT=0"
    )
    sent = [
        r.data["fields"]["param_id"]
        for r in recording.records()
        if isinstance(r, RecordedTopic)
        and r.name == "mavlink/tx"
        and r.data["type"] == "PARAM_REQUEST_READ"
    ]
    assert sorted(set(sent)) == sorted(FAILSAFE_PARAMETERS)


def test_mavsim_answers_param_set_and_read_as_arducopter_does() -> None:
    port = free_udp_port()
    with mavsim_thread(f"udpin:127.0.0.1:{port}") as sim:
        vehicle = MavlinkVehicle(MavlinkConfig(url=f"udpout:127.0.0.1:{port}"))
        try:
            vehicle.connect()
            assert vehicle.read_parameters(("FS_GCS_ENABLE", "NO_SUCH_PARAM"), 1.0) == {
                "FS_GCS_ENABLE": 1.0
            }  # a name the autopilot does not have goes unanswered
            target = vehicle.target
            assert target is not None
            vehicle.link.send(
                mavlink.MAVLink_param_set_message(
                    target[0], target[1], b"FS_GCS_ENABLE", 0.0, mavlink.MAV_PARAM_TYPE_REAL32
                )
            )
            del vehicle.parameters["FS_GCS_ENABLE"]
            assert vehicle.read_parameters(("FS_GCS_ENABLE",), 1.0) == {"FS_GCS_ENABLE": 0.0}
            assert sim.params["FS_GCS_ENABLE"] == 0.0
            assert preflight(vehicle).gcs_failsafe_off.startswith(
                "the autopilot's GCS failsafe is off (FS_GCS_ENABLE=0)"
            )
        finally:
            vehicle.close()


# -- 5. closed-loop replay of refused commands ------------------------------------------------

LINK_LOSS = (
    "    r = [api.executeBehavior('TAKE_OFF')]\n"
    "    r.append(api.executeBehavior('GO_TO_POINT', coordinates=[0, 40, 1]))\n"
    "    r.append(api.executeBehavior('ROTATE', angle=90))\n"
    "    r.append(api.executeBehavior('GO_TO_POINT', relative_coordinates=[1, 0, 0]))\n"
    "    r.append(api.executeBehavior('WAIT', duration=2))\n"
    "    r.append(api.executeBehavior('LAND'))\n"
    "    return r\n"
)


def replays_unchanged(record: Path, mission: Path, *, open_loop: bool = True) -> list[str]:
    """The differences of each replay of `record`, with `mission` for closed loop."""
    differences = []
    for options in (
        *([ReplayOptions(mode=Mode.open)] if open_loop else []),
        ReplayOptions(mode=Mode.closed, mission=str(mission)),
        ReplayOptions(mode=Mode.closed),  # the recorded command stream, no script
    ):
        replayed = replay_recording(record, options)
        assert replayed.diff is not None and replayed.diff.compared > 0, replayed.error
        differences += [f"{options.mode}: {d.message}" for d in replayed.diff.differences]
    return differences


def test_closed_loop_replays_a_refused_arming_as_it_was_flown(tmp_path: Path) -> None:
    port = free_udp_port()
    record = tmp_path / "f.mcap"
    mission = write_mission(tmp_path, TAKE_OFF_AND_LAND)
    with mavsim_thread(f"udpout:127.0.0.1:{port}", refuse=(400,)):
        result = fly(
            FlightConfig(mission=mission, connect=f"udpin:127.0.0.1:{port}", record=record)
        )
    assert [a.result for a in result.activations] == ["PROCESS_FAILURE", "REJECTED"]
    assert recorded_refusals(record)[0].message == (
        "MAV_CMD_COMPONENT_ARM_DISARM refused: TEMPORARILY_REJECTED"
    )
    assert replays_unchanged(record, mission) == []


def test_closed_loop_replays_commands_refused_during_a_link_loss(tmp_path: Path) -> None:
    port = free_udp_port()
    record = tmp_path / "f.mcap"
    mission = write_mission(tmp_path, LINK_LOSS)
    sim_settings = {"speed_factor": 3.0, "drop_heartbeats_at": 4.0, "drop_for": 6.0}
    with mavsim_thread(f"udpout:127.0.0.1:{port}", **sim_settings):
        result = fly(
            FlightConfig(
                mission=mission,
                connect=f"udpin:127.0.0.1:{port}",
                record=record,
                heartbeat_timeout=1.0,
            )
        )
    assert result.link_losses == 1
    failed = {a.behavior: a.detail for a in result.mission_failures()}
    assert "set_yaw: refused, link lost (no heartbeat for 1 s)" in failed["ROTATE"]
    assert [r.behavior for r in recorded_refusals(record)] == ["ROTATE", "GO_TO_POINT", "LAND"]
    # Closed loop only: open loop's stand-ins order a behavior's end and the next
    # command within one tick by their recorded sub-tick times, and about one flight in
    # three here shows ROTATE taking the capability GO_TO_POINT just released (a known
    # open-loop difference, left for the what-if work on transitions).
    assert replays_unchanged(record, mission, open_loop=False) == []
