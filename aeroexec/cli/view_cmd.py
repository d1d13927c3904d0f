"""`aeroexec view REC [REC2]`: a recording (or two side by side) in the Rerun viewer."""

from __future__ import annotations

from contextlib import AbstractContextManager
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from aeroexec.cli.app import app, error_line, guarded, say
from aeroexec.cli.options import allow_remote_option, deprecated_option, output_option, replaced
from aeroexec.errors import AeroexecError
from aeroexec.viz.viewer import DEFAULT_WEB_PORT

# rerun takes ~0.5 s to import: only `view` itself may pay for it, not every command.
if TYPE_CHECKING:
    from aeroexec.progress import Advance
    from aeroexec.viz.view import ViewReport


def _default_output(base: Path, new: Path | None) -> Path:
    from aeroexec.viz.view import RRD_SUFFIX, default_output

    if new is None:
        return default_output(base)
    return base.with_name(f"{base.stem}_vs_{new.stem}{RRD_SUFFIX}")


def _progress(description: str, total: int) -> AbstractContextManager[Advance]:
    from aeroexec.progress import progress_bar

    return progress_bar(f"converting {description}", total)


def _summary(report: ViewReport) -> None:
    for source in report.sources:
        stats = source.stats
        where = f" under {source.root}" if source.root != "/" else ""
        typer.echo(
            f"{source.file}{where}: {stats.records} messages, {stats.vehicle_states} vehicle "
            f"states, {stats.behavior_events} behavior events, {stats.rejections} rejected, "
            f"{len(stats.behaviors)} behaviors, {len(stats.capabilities)} capabilities"
        )
        if not source.complete:
            error_line(
                f"{source.file}: warning: incomplete recording: {source.problem}; "
                f"shown up to there (run `aeroexec recover` for a complete copy)"
            )
        for note in source.notes:
            error_line(f"{source.file}: note: {note}")


@app.command("view")
@guarded
def view(
    recording: Annotated[
        Path,
        typer.Argument(
            metavar="REC",
            help="An aeroexec recording (MCAP) or a ROS 1 or ROS 2 bag (imported on the way).",
            show_default=False,
        ),
    ],
    other: Annotated[
        Path | None,
        typer.Argument(
            metavar="REC2",
            help="A second recording, shown beside REC (e.g. its replay) on the same sim_time.",
            show_default=False,
        ),
    ] = None,
    output: Path | None = output_option(
        "Write the Rerun file (.rrd) here (default: <REC stem>.rrd next to REC)."
    ),
    save: Path | None = deprecated_option("--save", instead="-o/--output"),
    spawn: Annotated[
        bool | None,
        typer.Option(
            "--spawn/--no-spawn",
            help="Open the Rerun viewer on the result (default: yes unless -o is given).",
            show_default=False,
        ),
    ] = None,
    web: Annotated[
        bool,
        typer.Option(
            "--web",
            help="Serve the web viewer instead (no display needed) until Ctrl-C; it stops "
            "when aeroexec does.",
        ),
    ] = False,
    port: Annotated[
        int | None,
        typer.Option(
            "--port",
            metavar="PORT",
            min=0,
            max=65535,
            help=f"The web viewer's port (default {DEFAULT_WEB_PORT}; 0: any free port).",
            show_default=False,
        ),
    ] = None,
    allow_remote: bool = allow_remote_option(
        "Serve the web viewer on every network interface, not only this machine (127.0.0.1)."
    ),
) -> None:
    """Show a session in Rerun: the flight in 3D (world markers, vehicle pose, trajectory),
    one lane per behavior with each activation, capability reference counts, and the
    events, rejected activations, errors and service call tree as logs, on a `sim_time`
    timeline (service calls also on `seq`).

    With REC2, both sessions sit side by side (under /base and /new), aligned on sim_time:
    a base run and its replay under a new catalog, say. A ROS 1 or ROS 2 bag is imported
    first (the shipped Aerostack or Aerostack2 mapping; `aeroexec import --mapping` for
    others).

    The Rerun file is written to -o/--output, or next to REC (<REC stem>.rrd; two recordings:
    <REC stem>_vs_<REC2 stem>.rrd). The viewer opens on it when it can run (the rerun
    binary of rerun-sdk and a display); otherwise the command says so and where the file
    is. Open it later with `rerun FILE.rrd`. --web serves the web viewer on
    http://127.0.0.1:PORT (this machine only, unless --allow-remote) until Ctrl-C.

    \b
    Examples:
      aeroexec view flight.mcap
      aeroexec view base.mcap replay.mcap -o diff.rrd
      aeroexec view flight.bag --web --port 9091

    Exit codes: 0 written (and viewer started when asked); 1 the web viewer failed while
    serving; 2 a recording could not be read (not MCAP, not an aeroexec recording, nothing
    readable), the file not written or the web viewer's port taken; 128+N stopped by
    signal N (the web viewer with it).
    """
    output = replaced(output, save, new_name="-o/--output", old_name="--save")
    if not web and (port is not None or allow_remote):
        raise AeroexecError("--port and --allow-remote are for the web viewer: add --web")
    chosen = output is not None
    if output is None:
        output = _default_output(recording, other)
    inputs = [recording] if other is None else [recording, other]

    from aeroexec.viz import viewer
    from aeroexec.viz.view import write_view

    report = write_view(inputs, output, progress=_progress)
    _summary(report)
    typer.echo(f"wrote {report.output}")
    want_viewer = web or (spawn if spawn is not None else not chosen)
    if not want_viewer:
        return
    reason = viewer.cannot_spawn(web=web)
    if reason is not None:
        say("note", f"viewer not started: {reason}. Open the file with `rerun {report.output}`")
        return
    if not web:
        typer.echo("opening the Rerun viewer")
        viewer.open_viewer(report.output)
        return
    status = viewer.serve_web(
        report.output,
        bind=viewer.ALL_INTERFACES if allow_remote else viewer.LOOPBACK,
        port=DEFAULT_WEB_PORT if port is None else port,
        on_ready=lambda url, _pid: typer.echo(f"serving the web viewer at {url} (Ctrl-C to stop)"),
    )
    if status != 0:
        say("error", f"the web viewer ended with exit status {status}")
        raise typer.Exit(1)
