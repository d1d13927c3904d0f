"""`aeroexec verify`: check catalogs (and the missions that use them) before flight."""

from __future__ import annotations

import os
import sys

import typer

from aeroexec.catalog.model import Severity
from aeroexec.cli.app import app, error_line, guarded
from aeroexec.cli.project import BehaviorsOption, first, project, project_behaviors
from aeroexec.errors import AeroexecError
from aeroexec.vehicles.world import load_world
from aeroexec.verifier import verify
from aeroexec.verifier.registry import get, suggest_code
from aeroexec.verifier.report import FORMATS, render

HELP = """Check behavior catalogs and mission scripts offline, before they fly.

Every catalog is read leniently (all problems reported, not just the first) and
checked by the rules of the registry: dangling references, capability conflicts that
stop behaviors or initiation, one-sided incompatibilities, start-order cycles,
recurrent/timeout contradictions, targets the vehicle cannot reach in time, dead lists
and capabilities. Aerostack 4.x task catalogs (2020-2021) are read into their own
model and judged as the 2021 task coordinator would. Mission scripts given with
--mission are read with Python's ast (never run): constants, loops over names, helper
functions and API aliases are folded, every call is checked against each behavior
catalog, and the calls are run as sequences, path by path, in the executive (preempted
inhibits, capability conflicts, flight state, behaviors left running). An input that
cannot be read is reported (one line on stderr, and in the json/sarif/github output)
and the others are verified all the same; the exit code is then 2.

When the project declares its behaviors (-b/--behaviors, `behaviors` in
[tool.aeroexec] or aeroexec.toml, an installed 'aeroexec.behaviors' entry point), each
catalog is also checked against that code (AX9xx: behaviors without an implementation,
argument names the code does not read), and witnesses are completed to happen with the
real behaviors (TAKE_OFF first, arguments). Without CATALOG, the project's catalog.

\b
Examples:
  aeroexec verify catalog/default.yaml
  aeroexec verify catalog/*.yaml --mission 'missions/*.py' --witness
  aeroexec verify config/mission/behavior_catalog.yaml   # a 2020-2021 task catalog
  aeroexec verify catalog/default.yaml -m mission.py --world worlds/field.yaml
  aeroexec verify catalog/default.yaml --format sarif > verify.sarif
  aeroexec verify my-catalog.yaml -b mybehaviors
  aeroexec verify --explain AX304

\b
Exit codes: 0 no errors; 1 errors (or warnings with --strict);
            2 an input could not be read (one line each on stderr).
"""


def _use_color(choice: str | None) -> bool:
    if choice is not None:
        return choice == "always"
    if os.environ.get("NO_COLOR"):
        return False
    return sys.stdout.isatty()


@app.command("verify", help=HELP)
@guarded
def verify_command(
    catalogs: list[str] = typer.Argument(
        None, metavar="CATALOG...", help="Catalog files (YAML); glob patterns allowed."
    ),
    mission: list[str] = typer.Option(
        [],
        "--mission",
        "-m",
        metavar="PATH",
        help="Mission script or glob (repeatable); checked against every catalog.",
    ),
    output_format: str = typer.Option(
        "text", "--format", "-f", metavar="FORMAT", help="text, json, sarif or github."
    ),
    world: str | None = typer.Option(
        None,
        "--world",
        "-w",
        metavar="FILE",
        help="World file whose vehicle limits the reach checks use (default: built-in).",
    ),
    strict: bool = typer.Option(False, "--strict", help="Exit 1 on warnings too."),
    witness: bool = typer.Option(
        False, "--witness", help="Print each finding's witness activation sequence."
    ),
    min_severity: str | None = typer.Option(
        None,
        "--min-severity",
        metavar="LEVEL",
        help="Show findings from this level up: info, warning or error "
        "(default: warning for text and github, info for json and sarif).",
    ),
    explain: str | None = typer.Option(
        None, "--explain", metavar="CODE", help="Print a rule's documentation and exit."
    ),
    color: str | None = typer.Option(
        None, "--color", metavar="WHEN", help="always or never (default: on a terminal)."
    ),
    behaviors: BehaviorsOption = None,
) -> None:
    if explain is not None:
        rule = get(explain)
        if rule is None:
            raise AeroexecError(f"unknown rule code {explain!r}{suggest_code(explain)}")
        typer.echo(rule.explain())
        return
    if output_format not in FORMATS:
        raise AeroexecError(f"unknown format {output_format!r} (formats: {', '.join(FORMATS)})")
    if min_severity is None:
        min_severity = "info" if output_format in ("json", "sarif") else "warning"
    try:
        threshold = Severity(min_severity)
    except ValueError:
        raise AeroexecError(f"unknown severity {min_severity!r} (info, warning or error)") from None
    if color not in (None, "always", "never"):
        raise AeroexecError(f"--color takes always or never, got {color!r}")
    settings = project()
    if not catalogs and settings.catalog is not None:
        catalogs = [str(settings.catalog)]
    if not catalogs:
        raise AeroexecError("no catalog given (try: aeroexec verify catalog.yaml)")
    found = project_behaviors(behaviors, settings)
    world_path = first(world, settings.world, None)
    limits = load_world(world_path) if world_path is not None else None
    report = verify(catalogs, mission, world=limits, behaviors=found if found.declared else None)
    shown = report.at_least(threshold)
    use_color = _use_color(color)
    text = render(shown, output_format, witness=witness, color=use_color)
    typer.echo(text, nl=False, color=use_color)
    for error in report.input_errors:
        error_line(str(error))
    # The exit code counts every finding, shown or not, and every unreadable input.
    raise typer.Exit(report.exit_code(strict))
