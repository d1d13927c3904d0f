"""`aeroexec check REC...`: evaluate properties (signal temporal logic) on recordings."""

from __future__ import annotations

from enum import Enum
from typing import Annotated

import typer

from aeroexec.cli.app import app, guarded
from aeroexec.cli.options import format_option
from aeroexec.cli.spec import SpecOption
from aeroexec.errors import PropertyError
from aeroexec.properties import report as render
from aeroexec.properties.check import check_recording
from aeroexec.properties.spec import load_properties

HELP = """Check recordings against properties in signal temporal logic (STL): what must
always hold in a flight, such as `always(altitude <= 120)`. Without --spec the built-in
set aeroexec:safety is checked; docs/properties.md lists the signals.

\b
Example:
  aeroexec check flight.mcap --spec spec.yaml
  aeroexec check runs/*.mcap --spec aeroexec:safety --spec spec.yaml -f junit
  aeroexec check --spec spec.yaml --explain ceiling

\b
Exit codes: 0 every property holds; 1 a property of severity error was
            violated; 2 a recording or property file could not be read.
"""


class CheckFormat(str, Enum):
    text = "text"
    json = "json"
    sarif = "sarif"
    junit = "junit"
    github = "github"


@app.command("check", help=HELP)
@guarded
def check(
    recordings: Annotated[
        list[str] | None,
        typer.Argument(metavar="REC...", help="Recordings (MCAP).", show_default=False),
    ] = None,
    spec: SpecOption = None,
    output_format: CheckFormat = format_option(
        CheckFormat,
        "text: one line per violation; json; sarif; junit (JUnit XML); github "
        "(workflow annotations).",
    ),
    explain: Annotated[
        str | None,
        typer.Option(
            "--explain",
            metavar="CODE",
            help="Print a property, by its name (formula, signals and their units) and exit.",
            show_default=False,
        ),
    ] = None,
) -> None:
    properties = load_properties(spec or ["aeroexec:safety"])
    if explain is not None:
        prop = properties.find(explain)
        if prop is None:
            names = ", ".join(p.name for p in properties.properties)
            raise PropertyError(f"no property '{explain}' (there are: {names})")
        typer.echo(render.explain(prop, properties.parameters), nl=False)
        return
    if not recordings:
        raise PropertyError("no recording given (try: aeroexec check flight.mcap)")
    reports = [check_recording(path, properties) for path in recordings]
    if output_format is CheckFormat.json:
        out = render.as_json(reports)
    elif output_format is CheckFormat.sarif:
        out = render.sarif(reports)
    elif output_format is CheckFormat.junit:
        out = render.junit(reports)
    elif output_format is CheckFormat.github:
        out = render.github(reports)
    else:
        out = render.text(reports)
    typer.echo(out, nl=False)
    if any(r.failed for r in reports):
        raise typer.Exit(1)
