"""`aeroexec fly MISSION --connect URL`: run a mission script on a live autopilot."""

from __future__ import annotations

from dataclasses import replace
from enum import Enum
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from aeroexec.catalog.paths import DEFAULT_CATALOG
from aeroexec.cli.app import app, error_line, guarded
from aeroexec.cli.command import running
from aeroexec.cli.live import (
    LiveOption,
    PortOption,
    RerunPortOption,
    WaitViewerOption,
    live_view,
)
from aeroexec.cli.options import (
    Color,
    allow_remote_option,
    apply_timeout,
    catalog_option,
    choices,
    color_option,
    connect_option,
    debug_option,
    deprecated_option,
    output_option,
    quiet_option,
    replaced,
    timeout_option,
    use_color,
)
from aeroexec.cli.project import (
    AllowUnimplementedOption,
    BehaviorsOption,
    DisablePluginOption,
    catalog_path,
    first,
    project,
    project_behaviors,
)
from aeroexec.cli.run_cmd import print_row, print_summary, report_outcome, silenced
from aeroexec.cli.spec import SpecOption, monitor_for, print_verdicts
from aeroexec.executive.bus import BusObserver
from aeroexec.executive.clock import NS_PER_S
from aeroexec.executive.messages import ServiceCallRecord, TopicRecord
from aeroexec.mission.activity import ActivityLog
from aeroexec.mission.live import FlightConfig, fly
from aeroexec.vehicles.mavlink.endpoint import DEFAULT_BAUD, DEFAULT_GCS_URL
from aeroexec.vehicles.mavlink.vehicle import MavlinkVehicle

if TYPE_CHECKING:
    from aeroexec.viz.live import LiveView


class Failsafe(str, Enum):
    land = "land"
    hold = "hold"
    rtl = "rtl"


class AutopilotTexts:
    """Prints the autopilot's warnings and errors (STATUSTEXT: "Arm: Battery 1 below
    minimum arming voltage", "PreArm: ...") as they arrive: they are why the vehicle
    did not do what it was told."""

    def on_service_call(self, record: ServiceCallRecord) -> None:
        pass

    def on_topic(self, record: TopicRecord) -> None:
        data = record.data
        if (
            record.topic == "log"
            and data.get("name") == "mavlink"
            and data.get("level") in ("WARNING", "ERROR")
            and str(data.get("message", "")).startswith("autopilot: ")
        ):
            typer.echo(f"[{record.log_time_ns / NS_PER_S:7.1f} s] {data['message']}")


class OnExit(str, Enum):
    land = "land"
    hold = "hold"
    none = "none"


def _listening(vehicle: MavlinkVehicle) -> None:
    typer.echo(
        f"mavlink: {vehicle.endpoint.url} (local {vehicle.link.local_text}), "
        "waiting for a heartbeat..."
    )


def _connected(vehicle: MavlinkVehicle) -> None:
    target = vehicle.target or (0, 0)
    t = vehicle.telemetry
    typer.echo(
        f"mavlink: autopilot system {target[0]} component {target[1]}, mode {t.mode}, "
        f"{'armed' if t.armed else 'disarmed'}"
    )


@app.command("fly")
@guarded
def fly_command(
    mission: Path = typer.Argument(
        ..., metavar="MISSION", help="Mission script (Python, defines runMission())."
    ),
    connect: str | None = connect_option(
        None,
        "MAVLink endpoint: udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT, "
        "tcpin:HOST:PORT, or a serial device (/dev/ttyUSB0 or /dev/ttyUSB0,57600); "
        f"default: the project's, else {DEFAULT_GCS_URL}.",
    ),
    baud: int = typer.Option(
        DEFAULT_BAUD,
        "--baud",
        metavar="N",
        help="Baud rate of a serial device given without one.",
        show_default=True,
    ),
    catalog: Path | None = catalog_option(
        "Behavior catalog (YAML); default: the project's, else the bundled default."
    ),
    output: Path | None = output_option(
        "Record the session (and all MAVLink traffic) to this MCAP file."
    ),
    record: Path | None = deprecated_option("--record", "-r", instead="-o/--output"),
    heartbeat_timeout: float = typer.Option(
        3.0,
        "--heartbeat-timeout",
        metavar="SECONDS",
        help="Seconds without an autopilot heartbeat = link lost.",
        show_default=True,
    ),
    link_timeout: float = typer.Option(
        30.0,
        "--link-timeout",
        metavar="SECONDS",
        help="A link lost this long ends the flight (fly waits that long for it to return).",
        show_default=True,
    ),
    failsafe: Failsafe = typer.Option(
        Failsafe.land,
        "--failsafe",
        metavar=choices(Failsafe),
        help="What to do when a lost link returns.",
        show_default=True,
    ),
    on_exit: OnExit = typer.Option(
        OnExit.land,
        "--on-exit",
        metavar=choices(OnExit),
        help="How the flight ends when the mission returns, raises or is stopped by a signal.",
        show_default=True,
    ),
    signing_key: str | None = typer.Option(
        None,
        "--signing-key",
        metavar="KEY",
        help="MAVLink 2 signing: 64 hex digits or a passphrase.",
        show_default=False,
    ),
    allow_remote: bool = allow_remote_option(
        "Allow a non-loopback endpoint (a real network); with --live, serve on every "
        "network interface too."
    ),
    allow_no_gcs_failsafe: bool = typer.Option(
        False,
        "--allow-no-gcs-failsafe",
        help="Fly although the autopilot's GCS failsafe is off (FS_GCS_ENABLE=0): nothing "
        "brings the vehicle down if fly stops. Without it fly refuses before arming.",
    ),
    connect_timeout: float = typer.Option(
        10.0,
        "--connect-timeout",
        metavar="SECONDS",
        help="Seconds to wait for the first heartbeat and position (SITL needs ~40 s to boot).",
        show_default=True,
    ),
    behaviors: BehaviorsOption = None,
    timeout: float | None = timeout_option(
        "Stop the mission when it has run this long in wall-clock time (for one that "
        "stops yielding: a loop, a sleep): it fails at its file:line, exit 1; also limits "
        "importing -b/--behaviors (exit 2). Default: no limit; 0: none."
    ),
    disable_plugin: DisablePluginOption = None,
    allow_unimplemented: AllowUnimplementedOption = False,
    spec: SpecOption = None,
    live: LiveOption = False,
    port: PortOption = None,
    rerun_port: RerunPortOption = None,
    wait_viewer: WaitViewerOption = False,
    quiet: bool = quiet_option(),
    debug: bool = debug_option(),
    color: Color = color_option(),
) -> None:
    """Fly MISSION on a live autopilot (ArduPilot Copter, GUIDED mode) over MAVLink.

    The live counterpart of `aeroexec run`: same core, same behaviors, same printout,
    on the wall clock.

    \b
    Examples (mavsim, then ArduCopter SITL, which takes ~40 s to boot):
      aeroexec mavsim --speed-factor 3 &
      aeroexec fly missions/appendix_c.py -o flight.mcap
      aeroexec fly missions/appendix_c.py --connect tcp:127.0.0.1:5760 \\
          --connect-timeout 60

    With --live the flight is served as it happens (Foxglove, Lichtblick:
    ws://127.0.0.1:8765; with --rerun-port 9876, Rerun too: rerun
    rerun+http://127.0.0.1:9876/proxy); a viewer may call /abort_mission, and the flight
    ends as --on-exit says.

    However it ends, the vehicle is never left flying by surprise: see --on-exit,
    --failsafe and --link-timeout. Exit code 0 when the mission returned and the vehicle
    ended landed and disarmed with the link never lost; 1 when the mission raised, a
    behavior ended PROCESS_FAILURE (the autopilot refused a command, or the vehicle had
    a fault), the link was lost, the vehicle did not end landed and disarmed or a step of
    its ending was not seen in the autopilot's telemetry within its bound; 2 when
    an input could not be read or the autopilot never answered; 128+N when stopped by
    signal N (after the ending).
    """
    apply_timeout(timeout)
    output = replaced(output, record, new_name="-o/--output", old_name="-r/--record")
    settings = project()
    config = FlightConfig(
        mission=mission,
        connect=first(connect, settings.connect, DEFAULT_GCS_URL),
        catalog=catalog_path(catalog, settings, DEFAULT_CATALOG),
        record=output,
        heartbeat_timeout=heartbeat_timeout,
        failsafe=failsafe.value,
        on_exit=on_exit.value,
        link_timeout=link_timeout,
        signing_key=signing_key,
        allow_remote=allow_remote,
        connect_timeout=connect_timeout,
        behaviors=project_behaviors(behaviors, settings, disable_plugin),
        allow_unimplemented=allow_unimplemented,
        baud=baud,
        allow_no_gcs_failsafe=allow_no_gcs_failsafe,
    )
    with live_view(
        live,
        port=port,
        rerun_port=rerun_port,
        wait_viewer=wait_viewer,
        allow_remote=allow_remote,
        abort_action=on_exit.value,
        output=output,
    ) as view:
        _fly(replace(config, tap=view), mission, spec, quiet, debug, color, view)


def _fly(
    config: FlightConfig,
    mission: Path,
    spec: SpecOption,
    quiet: bool,
    debug: bool,
    color: Color,
    view: LiveView | None,
) -> None:
    monitor = monitor_for(spec, live=True)
    observers: list[BusObserver] = [AutopilotTexts()]
    if not quiet:
        observers.append(ActivityLog(on_change=print_row))
    if monitor is not None:
        observers.append(monitor)
    if view is not None:
        observers.append(view)
    with silenced(quiet):
        result = fly(
            config,
            observers=observers,
            on_listening=_listening,
            on_connected=_connected,
            on_preflight=typer.echo,
            announce=error_line,
        )
    print_summary(result, clock="flown", styled=use_color(color))
    typer.echo(f"mavlink: {result.metadata.get('link_summary', '')}")
    if result.ending is not None:
        for action in result.ending.actions:
            typer.echo(f"ending: {action}")
        typer.echo(f"ending: vehicle {result.ending.last_seen}")
    # The flight's own ending says what became of the vehicle (last, in one line): the
    # simulator's "vehicle lost" verdict is not needed here.
    violated = False
    if monitor is not None:
        violated = print_verdicts(monitor.verdicts, result.recording or str(mission))
    mission_ok = report_outcome(result, debug, vehicle=False)
    for failed in result.mission_failures():
        error_line(
            f"{running()}: mission failed: {failed.behavior} ended PROCESS_FAILURE: {failed.detail}"
        )
        mission_ok = False
    if not result.safe:
        error_line(f"{running()}: {result.problem()}")
    if not (mission_ok and result.safe) or violated:
        raise typer.Exit(1)
