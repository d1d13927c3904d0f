"""`aeroexec run MISSION`: run a mission script against the simulated vehicle."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from aeroexec.catalog.paths import DEFAULT_CATALOG
from aeroexec.cli.app import app, error_line, guarded
from aeroexec.cli.live import (
    LiveOption,
    PortOption,
    RerunPortOption,
    WaitViewerOption,
    live_speed,
    live_view,
)
from aeroexec.cli.options import (
    Color,
    allow_remote_option,
    apply_timeout,
    catalog_option,
    color_option,
    debug_option,
    deprecated_option,
    output_option,
    quiet_option,
    replaced,
    seed_option,
    timeout_option,
    use_color,
    world_option,
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
from aeroexec.cli.spec import SpecOption, monitor_for, print_verdicts
from aeroexec.cli.tables import print_table
from aeroexec.config import ProjectConfig
from aeroexec.errors import AeroexecError
from aeroexec.executive.bus import BusObserver
from aeroexec.executive.clock import NS_PER_S
from aeroexec.mission.activity import Activation, ActivityLog, format_arguments
from aeroexec.mission.script import Ending
from aeroexec.mission.session import (
    DEFAULT_MAX_SIM_TIME_S,
    SessionConfig,
    SessionResult,
    simulate,
)

if TYPE_CHECKING:
    from aeroexec.viz.live import LiveView


def print_row(row: Activation) -> None:
    args = format_arguments(row.arguments)
    if not row.accepted:
        typer.echo(f"[{row.start_s:7.1f} s] REJECTED {row.behavior} {args}: {row.error}")
    elif row.end_ns is None:
        typer.echo(f"[{row.start_s:7.1f} s] start    {row.behavior} {args}".rstrip())
    else:
        took = (row.end_s or 0.0) - row.start_s
        detail = f" ({row.detail})" if row.detail and row.end_code != "GOAL_ACHIEVED" else ""
        typer.echo(
            f"[{row.end_s:7.1f} s] end      {row.behavior} {row.end_code} "
            f"after {took:.1f} s{detail}"
        )


def print_fault(time_ns: int, fault: str) -> None:
    what = f"FAULT    vehicle: {fault}" if fault else "fault cleared"
    typer.echo(f"[{time_ns / NS_PER_S:7.1f} s] {what}")


@contextlib.contextmanager
def silenced(quiet: bool) -> Iterator[None]:
    """With -q, what the mission script prints goes nowhere (its errors still do)."""
    if not quiet:
        yield
        return
    with open(os.devnull, "w", encoding="utf-8") as nowhere, contextlib.redirect_stdout(nowhere):
        yield


def print_summary(result: SessionResult, clock: str = "simulated", styled: bool = False) -> None:
    """The summary table and one line of totals; `clock` says whose seconds they are."""
    rows = [
        [
            str(i),
            a.behavior,
            format_arguments(a.arguments),
            a.result,
            f"{a.start_s:.1f}",
            "" if a.end_s is None else f"{a.end_s:.1f}",
            "" if a.end_s is None else f"{a.end_s - a.start_s:.1f}",
        ]
        for i, a in enumerate(result.activations, 1)
    ]
    print_table(
        "Behaviors",
        ["#", "behavior", "arguments", "result", "start s", "end s", "took s"],
        rows,
        styled=styled,
    )
    achieved = sum(a.end_code == "GOAL_ACHIEVED" for a in result.activations)
    rejected = sum(not a.accepted for a in result.activations)
    x, y, z = result.final_state.position
    state = "flying" if result.final_state.flying else "landed"
    fault = f", fault {result.vehicle_lost}" if result.vehicle_lost else ""
    typer.echo(
        f"{len(result.activations)} activations: {achieved} GOAL_ACHIEVED, {rejected} rejected; "
        f"{result.duration_s:.1f} s {clock}; vehicle {state} at ({x:.2f}, {y:.2f}, {z:.2f})"
        f"{fault}"
    )


@app.command()
@guarded
def run(
    mission: Path = typer.Argument(
        ..., metavar="MISSION", help="Mission script (Python, defines runMission())."
    ),
    catalog: Path | None = catalog_option(
        "Behavior catalog (YAML); default: the project's, else the bundled default."
    ),
    seed: int | None = seed_option(),
    world: Path | None = world_option(
        "World file (markers, failures); default: the project's, else the built-in world."
    ),
    output: Path | None = output_option("Record the session to this MCAP file."),
    record: Path | None = deprecated_option("--record", "-r", instead="-o/--output"),
    behaviors: BehaviorsOption = None,
    timeout: float | None = timeout_option(
        "Stop the mission when it has run this long in wall-clock time (for one that "
        "stops yielding: a loop, a sleep): it fails at its file:line, exit 1; also limits "
        "importing -b/--behaviors (exit 2). Default: no limit; 0: none."
    ),
    disable_plugin: DisablePluginOption = None,
    allow_unimplemented: AllowUnimplementedOption = False,
    max_sim_time: float = typer.Option(
        DEFAULT_MAX_SIM_TIME_S,
        "--max-sim-time",
        metavar="SECONDS",
        min=0.0,
        help="Stop a mission that is still running after this much simulated time "
        "(default: 24 h; 0: no limit). Recorded as the reason the session ended.",
        show_default=False,
    ),
    spec: SpecOption = None,
    live: LiveOption = False,
    port: PortOption = None,
    rerun_port: RerunPortOption = None,
    wait_viewer: WaitViewerOption = False,
    speed: float | None = typer.Option(
        None,
        "--speed",
        metavar="FACTOR",
        help="Keep the simulated clock to the wall clock, FACTOR times as fast (default with "
        "--live: 1, real time; without: as fast as it computes). The session and its "
        "recording are the same at any speed.",
        show_default=False,
    ),
    allow_remote: bool = allow_remote_option(
        "With --live: serve on every network interface, not only this machine (127.0.0.1)."
    ),
    quiet: bool = quiet_option(),
    debug: bool = debug_option(),
    color: Color = color_option(),
) -> None:
    """Run MISSION in simulation: print each behavior as it starts and ends, then a summary.

    Example:

        aeroexec run missions/appendix_c.py -o flight.mcap
        aeroexec run missions/appendix_c.py -o flight.mcap --live --wait-viewer

    With --live the session is served as it happens (Foxglove, Lichtblick: connect to
    ws://127.0.0.1:8765; with --rerun-port 9876, Rerun too: rerun
    rerun+http://127.0.0.1:9876/proxy), at real time unless --speed; a viewer may call
    the service /abort_mission, and the vehicle lands.

    Behaviors come from -b/--behaviors, the project's [tool.aeroexec] table (nearest
    pyproject.toml or aeroexec.toml), installed 'aeroexec.behaviors' entry points and the
    standard library.

    Exit code 0 when the mission function returned (or called sys.exit() or sys.exit(0))
    with the vehicle healthy; 1 when it raised, called sys.exit() with another code, ran
    past --max-sim-time or --timeout or lost its vehicle (a fault such as an empty
    battery); 2 when an input (mission, catalog, world, configuration, behaviors) could not
    be used, a catalog behavior has no implementation, or the recording could not be
    written; 128+N when stopped by signal N (the first signal is enough).
    """
    apply_timeout(timeout)
    output = replaced(output, record, new_name="-o/--output", old_name="-r/--record")
    speed = live_speed(speed, live)
    if allow_remote and not live:
        raise AeroexecError("--allow-remote is for --live: add --live")
    settings = project()
    with live_view(
        live,
        port=port,
        rerun_port=rerun_port,
        wait_viewer=wait_viewer,
        allow_remote=allow_remote,
        abort_action="land",
        output=output,
    ) as view:
        _run(
            mission,
            catalog,
            seed,
            world,
            output,
            behaviors,
            disable_plugin,
            allow_unimplemented,
            max_sim_time,
            spec,
            quiet,
            debug,
            color,
            settings,
            view,
            speed,
        )


def _run(
    mission: Path,
    catalog: Path | None,
    seed: int | None,
    world: Path | None,
    output: Path | None,
    behaviors: BehaviorsOption,
    disable_plugin: DisablePluginOption,
    allow_unimplemented: bool,
    max_sim_time: float,
    spec: SpecOption,
    quiet: bool,
    debug: bool,
    color: Color,
    settings: ProjectConfig,
    view: LiveView | None,
    speed: float | None,
) -> None:
    config = SessionConfig(
        mission=mission,
        catalog=catalog_path(catalog, settings, DEFAULT_CATALOG),
        seed=first(seed, settings.seed, 0),
        world=first(world, settings.world, None),
        record=output,
        behaviors=project_behaviors(behaviors, settings, disable_plugin),
        allow_unimplemented=allow_unimplemented,
        max_sim_time_s=max_sim_time or None,
        tap=view,
        speed=speed,
    )
    monitor = monitor_for(spec)
    observers: list[BusObserver] = (
        [] if quiet else [ActivityLog(on_change=print_row, on_fault=print_fault)]
    )
    if monitor is not None:
        observers.append(monitor)
    if view is not None:
        observers.append(view)
    with silenced(quiet):
        result = simulate(config, observers=observers, announce=error_line)
    print_summary(result, styled=use_color(color))
    violated = False
    if monitor is not None:
        violated = print_verdicts(monitor.verdicts, result.recording or str(mission))
    finish(result, debug, violated)


def finish(result: SessionResult, debug: bool, violated: bool = False) -> None:
    """Say where the recording is, and exit 1 (with the reason, at the mission's own
    file:line) if the mission did not end well, lost its vehicle or violated a
    property of --spec."""
    if not report_outcome(result, debug, vehicle=True) or violated:
        raise typer.Exit(1)


def report_outcome(result: SessionResult, debug: bool, vehicle: bool) -> bool:
    """Say where the recording is and, on stderr, why the mission did not end well (and,
    with `vehicle`, that it lost its vehicle); True if it ended well."""
    if result.recording:
        typer.echo(f"recorded to {result.recording}")
    outcome = result.outcome
    if not outcome.returned:
        if debug and outcome.traceback:
            typer.echo(outcome.traceback, err=True)
        where = f"{outcome.where}: " if outcome.where else ""
        if outcome.ending is Ending.TIME_LIMIT:
            error_line(f"{where}mission stopped: {outcome.error} (--max-sim-time)")
        elif outcome.ending is Ending.TIMEOUT:
            error_line(f"{where}mission stopped: {outcome.error}")
        elif outcome.ending.stopped:
            done = "; ".join(getattr(result, "assurance", ()) or ())
            error_line(f"mission stopped: {outcome.error}" + (f" ({done})" if done else ""))
        else:
            error_line(f"{where}mission failed: {outcome.error}")
        return False
    if vehicle and result.vehicle_lost:
        since = next(
            (t for t, fault in reversed(result.faults) if fault == result.vehicle_lost), None
        )
        at = f" at {since / NS_PER_S:.1f} s" if since is not None else ""
        error_line(f"mission failed: the vehicle was lost: fault {result.vehicle_lost}{at}")
        return False
    return True
