"""`--live` on `run`, `fly` and `replay`: the options, and the live view around the
session.

The servers (aeroexec/viz/live.py) import foxglove-sdk (and rerun-sdk for the Rerun
stream): they are imported only when `--live` is given (and `--rerun-port`), so the
commands start as fast as before without it.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from aeroexec.errors import AeroexecError

if TYPE_CHECKING:
    from aeroexec.viz.live import LiveView

#: The defaults of aeroexec/viz/live.py, here so that `-h` needs no import of it.
FOXGLOVE_PORT = 8765
RERUN_PORT = 9876

LiveOption = Annotated[
    bool,
    typer.Option(
        "--live",
        help="Serve the session as it happens: a Foxglove WebSocket server (Foxglove, "
        "Lichtblick) and, with --rerun-port, a Rerun gRPC stream, on this machine only "
        "(127.0.0.1) unless --allow-remote. They carry what is recorded, and close when "
        "the command ends.",
    ),
]
PortOption = Annotated[
    int | None,
    typer.Option(
        "--port",
        metavar="PORT",
        min=0,
        max=65535,
        help=f"With --live: the Foxglove WebSocket server's port (default {FOXGLOVE_PORT}; "
        "0: any free port).",
        show_default=False,
    ),
]
RerunPortOption = Annotated[
    int | None,
    typer.Option(
        "--rerun-port",
        metavar="PORT",
        min=0,
        max=65535,
        help=f"With --live: stream to Rerun too, from a gRPC server on this port (Rerun's "
        f"usual one is {RERUN_PORT}; 0: any free port). Only when asked for: it costs "
        "most of the live view's CPU.",
        show_default=False,
    ),
]
WaitViewerOption = Annotated[
    bool,
    typer.Option(
        "--wait-viewer",
        help="With --live: start the mission only once a viewer has subscribed (so it "
        "misses nothing).",
    ),
]


def check_live_options(
    live: bool, port: int | None, rerun_port: int | None, wait_viewer: bool
) -> None:
    if not live and (port is not None or rerun_port is not None or wait_viewer):
        raise AeroexecError("--port, --rerun-port and --wait-viewer are for --live: add --live")


def live_speed(speed: float | None, live: bool) -> float | None:
    """The pacing `--speed` asks for, checked: with --live real time (1) unless given;
    without, as fast as it computes (None) unless given."""
    if speed is not None and not (speed > 0 and math.isfinite(speed)):
        raise AeroexecError(f"invalid value for --speed: {speed:g}: give a factor above 0")
    return speed if speed is not None or not live else 1.0


@contextmanager
def live_view(
    live: bool,
    *,
    port: int | None,
    rerun_port: int | None,
    wait_viewer: bool,
    allow_remote: bool,
    abort_action: str,
    output: Path | None,
) -> Iterator[LiveView | None]:
    """The live view while the block runs (None without --live); its servers are
    stopped however the block ends."""
    check_live_options(live, port, rerun_port, wait_viewer)
    if not live:
        yield None
        return
    from aeroexec.viz.live import LiveOptions, LiveView, loopback_or

    options = LiveOptions(
        host=loopback_or(allow_remote),
        port=FOXGLOVE_PORT if port is None else port,
        rerun_port=rerun_port,
        wait_viewer=wait_viewer,
        abort_action=abort_action,
    )
    view = LiveView(options, label=output.name if output is not None else "live")
    try:
        foxglove_url, rerun_url = view.urls
        typer.echo(f"live: Foxglove, Lichtblick: {foxglove_url}")
        if rerun_url is not None:
            typer.echo(f"live: Rerun: rerun {rerun_url}")
        if wait_viewer:
            typer.echo("live: the mission starts when a viewer subscribes")
        sys.stdout.flush()  # a script reading the addresses from a pipe gets them now
        yield view
    finally:
        view.close()
