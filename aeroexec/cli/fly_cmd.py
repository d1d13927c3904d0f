"""`aeroexec fly MISSION --connect URL`: run a mission script on a live autopilot."""

from __future__ import annotations

from pathlib import Path

import typer

from aeroexec.catalog.paths import DEFAULT_CATALOG
from aeroexec.cli.app import app, error_line, guarded
from aeroexec.cli.project import (
    AllowUnimplementedOption,
    BehaviorsOption,
    catalog_path,
    first,
    project,
    project_behaviors,
)
from aeroexec.cli.run_cmd import finish, print_row, print_summary
from aeroexec.mavlink.endpoint import DEFAULT_GCS_URL
from aeroexec.mavlink.vehicle import MavlinkVehicle
from aeroexec.mission.activity import ActivityLog
from aeroexec.mission.live import FlightConfig, fly


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
    connect: str | None = typer.Option(
        None,
        "--connect",
        help="MAVLink endpoint: udpin:HOST:PORT or udpout:HOST:PORT "
        f"(default: the project's, else {DEFAULT_GCS_URL}).",
    ),
    catalog: Path | None = typer.Option(
        None,
        "--catalog",
        "-c",
        help="Behavior catalog (YAML); default: the project's, else the bundled default.",
    ),
    record: Path | None = typer.Option(
        None,
        "--record",
        "-r",
        help="Record the session (and all MAVLink traffic) to this MCAP file.",
    ),
    heartbeat_timeout: float = typer.Option(
        3.0, "--heartbeat-timeout", help="Seconds without an autopilot heartbeat = link lost."
    ),
    failsafe: str = typer.Option(
        "hold", "--failsafe", help="What to do when a lost link returns: hold or land."
    ),
    signing_key: str | None = typer.Option(
        None, "--signing-key", help="MAVLink 2 signing: 64 hex digits or a passphrase."
    ),
    allow_remote: bool = typer.Option(
        False, "--allow-remote", help="Allow a non-loopback endpoint (a real network)."
    ),
    connect_timeout: float = typer.Option(
        10.0, "--connect-timeout", help="Seconds to wait for the first heartbeat."
    ),
    behaviors: BehaviorsOption = None,
    allow_unimplemented: AllowUnimplementedOption = False,
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Only the summary."),
    debug: bool = typer.Option(False, "--debug", help="Show the traceback if the mission raises."),
) -> None:
    """Fly MISSION on a live autopilot (ArduPilot Copter, GUIDED mode) over MAVLink.

    The live counterpart of `aeroexec run`: same core, same behaviors, same printout,
    on the wall clock. Try it against the simulator:

    \b
        aeroexec mavsim --speed-factor 3 &
        aeroexec fly missions/appendix_c.py --record flight.mcap

    Exit code 0 when the mission function returned, 1 when it raised, 2 when an input
    could not be read or the autopilot never answered.
    """
    settings = project()
    config = FlightConfig(
        mission=mission,
        connect=first(connect, settings.connect, DEFAULT_GCS_URL),
        catalog=catalog_path(catalog, settings, DEFAULT_CATALOG),
        record=record,
        heartbeat_timeout=heartbeat_timeout,
        failsafe=failsafe,  # type: ignore[arg-type]  (checked by FlightConfig)
        signing_key=signing_key,
        allow_remote=allow_remote,
        connect_timeout=connect_timeout,
        behaviors=project_behaviors(behaviors, settings),
        allow_unimplemented=allow_unimplemented,
    )
    printer = [] if quiet else [ActivityLog(on_change=print_row)]
    try:
        result = fly(
            config,
            observers=printer,
            on_listening=_listening,
            on_connected=_connected,
            announce=error_line,
        )
    except KeyboardInterrupt:
        error_line("aeroexec: interrupted (a flying vehicle was told to brake and hold)")
        raise typer.Exit(130) from None
    print_summary(result, clock="flown")
    typer.echo(f"mavlink: {result.metadata.get('link_summary', '')}")
    finish(result, debug)
