"""`aeroexec diff BASE NEW`: what changed between two recordings, per mission command."""

from __future__ import annotations

import time
from typing import Annotated

import typer

from aeroexec.cli.app import app, guarded
from aeroexec.cli.replay_cmd import (
    OutputFormat,
    PositionToleranceOption,
    ToleranceOption,
    report_format_option,
    tolerance_of,
)
from aeroexec.replay.engine import diff_recordings
from aeroexec.replay.report import diff_json, diff_junit, diff_text, start_timing


@app.command("diff")
@guarded
def diff(
    base: Annotated[
        str, typer.Argument(metavar="BASE", help="The reference recording.", show_default=False)
    ],
    new: Annotated[
        str, typer.Argument(metavar="NEW", help="The recording to compare.", show_default=False)
    ],
    output_format: OutputFormat = report_format_option(),
    tolerance: ToleranceOption = 0.5,
    position_tolerance: PositionToleranceOption = 0.1,
) -> None:
    """Compare two recordings mission command by mission command: accepted/rejected and
    why, preemptions, capability and process transitions, end events and their times
    (within --tolerance), the final vehicle state; and the commands only one of them has
    (the mission took another path).

    \b
    Example:
      aeroexec diff flight.mcap replayed.mcap --format json | jq '.differences'

    Exit codes: 0 no differences; 1 differences; 2 a recording could not be read.
    """
    # A JUnit report says when the run started (and checks SOURCE_DATE_EPOCH up front).
    timing = start_timing() if output_format is OutputFormat.junit else None
    started = time.perf_counter()
    result = diff_recordings(base, new, tolerance_of(tolerance, position_tolerance))
    if output_format is OutputFormat.json:
        typer.echo(diff_json(result))
    elif output_format is OutputFormat.junit:
        typer.echo(diff_junit(result, timing=timing, seconds=time.perf_counter() - started))
    else:
        typer.echo(diff_text(result))
    if not result.equal:
        raise typer.Exit(1)
