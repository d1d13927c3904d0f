"""`aeroexec verify`: check catalogs (and the missions that use them) before flight."""

from __future__ import annotations

import json
from enum import Enum

import typer

from aeroexec.catalog.model import Severity
from aeroexec.cli.app import app, error_line, guarded
from aeroexec.cli.options import (
    Color,
    choices,
    color_option,
    format_option,
    mission_option,
    use_color,
    world_option,
)
from aeroexec.cli.project import BehaviorsOption, first, project, project_behaviors
from aeroexec.errors import AeroexecError
from aeroexec.vehicles.world import load_world
from aeroexec.verifier import verify
from aeroexec.verifier.registry import all_rules, get, suggest_code
from aeroexec.verifier.report import render

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
and the others are verified all the same; the exit code is then 2. Text and github
output list at most --max-findings (100) findings per rule, then "... and N more";
json and sarif list them all, and every finding counts in the summary and exit code.

When the project declares its behaviors (-b/--behaviors, `behaviors` in
[tool.aeroexec] or aeroexec.toml, an installed 'aeroexec.behaviors' entry point), each
catalog is also checked against that code (AX9xx: behaviors without an implementation,
argument names the code does not read), and witnesses are completed to happen with the
real behaviors (TAKE_OFF first, arguments). Without CATALOG, the project's catalog.

\b
Examples:
  aeroexec verify catalog/default.yaml
  aeroexec verify catalog/*.yaml --mission 'missions/*.py' --witness
  aeroexec verify config/mission/behavior_catalog.yaml  # 2020-2021 tasks
  aeroexec verify catalog/default.yaml -m mission.py --world worlds/field.yaml
  aeroexec verify catalog/default.yaml --format sarif > verify.sarif
  aeroexec verify my-catalog.yaml -b mybehaviors
  aeroexec verify --list-rules
  aeroexec verify --explain AX304
  aeroexec verify huge.yaml --max-findings 0   # every finding, however many

\b
Exit codes: 0 no errors; 1 errors (or warnings with --strict);
            2 an input could not be read (one line each on stderr).
"""


#: Findings of one rule listed in text output before "... and N more": a screenful or
#: two, enough to see the pattern of a systematic mistake.
DEFAULT_MAX_FINDINGS = 100


def _non_negative(value: int) -> int:
    # A callback, not typer's `min=0`: that would import pydantic (start-up time).
    if value < 0:
        raise typer.BadParameter("must be 0 (no limit) or more")
    return value


class VerifyFormat(str, Enum):
    text = "text"
    json = "json"
    sarif = "sarif"
    github = "github"


class Level(str, Enum):
    info = "info"
    warning = "warning"
    error = "error"


@app.command("verify", help=HELP)
@guarded
def verify_command(
    catalogs: list[str] = typer.Argument(
        None,
        metavar="CATALOG...",
        help="Catalog files (YAML); glob patterns allowed. Default: the project's catalog.",
        show_default=False,
    ),
    mission: list[str] = mission_option(
        "Mission script or glob (repeatable); checked against every catalog.", repeatable=True
    ),
    output_format: VerifyFormat = format_option(
        VerifyFormat,
        "text: compiler-style lines; json; sarif (SARIF 2.1.0, for code scanning); "
        "github (workflow annotations).",
    ),
    world: str | None = world_option(
        "World file whose vehicle limits the reach checks use (default: built-in)."
    ),
    strict: bool = typer.Option(False, "--strict", help="Exit 1 on warnings too."),
    witness: bool = typer.Option(
        False, "--witness", help="Print each finding's witness activation sequence."
    ),
    min_severity: Level | None = typer.Option(
        None,
        "--min-severity",
        metavar=choices(Level),
        help="Show findings from this level up (default: warning for text and github, info "
        "for json and sarif).",
        show_default=False,
    ),
    explain: str | None = typer.Option(
        None,
        "--explain",
        metavar="CODE",
        help="Print a rule's documentation and exit.",
        show_default=False,
    ),
    list_rules: bool = typer.Option(
        False,
        "--list-rules",
        help="List every rule (code, severity, name, by area) and exit; with -f json, "
        "their documentation too.",
    ),
    max_findings: int = typer.Option(
        DEFAULT_MAX_FINDINGS,
        "--max-findings",
        metavar="N",
        callback=_non_negative,
        help="List at most N findings of each rule in text and github output, then "
        "'... and M more' (all are counted; json and sarif list them all); 0: no limit.",
    ),
    color: Color = color_option(),
    behaviors: BehaviorsOption = None,
) -> None:
    if explain is not None:
        rule = get(explain)
        if rule is None:
            raise AeroexecError(f"unknown rule code {explain!r}{suggest_code(explain)}")
        typer.echo(rule.explain())
        return
    if list_rules:
        typer.echo(rules_listing(output_format), nl=False)
        return
    fmt = output_format.value
    if min_severity is None:
        threshold = Severity.INFO if fmt in ("json", "sarif") else Severity.WARNING
    else:
        threshold = Severity(min_severity.value)
    settings = project()
    if not catalogs and settings.catalog is not None:
        catalogs = [str(settings.catalog)]
    if not catalogs:
        raise AeroexecError("no catalog given (try: aeroexec verify catalog.yaml)")
    found = project_behaviors(behaviors, settings)
    world_path = first(world, settings.world, None)
    limits = load_world(world_path) if world_path is not None else None
    # json and sarif are read by programs: every finding. Text and annotations are read
    # by people, who do not read a million lines of one rule.
    limit = max_findings if fmt in ("text", "github") and max_findings > 0 else None
    report = verify(
        catalogs,
        mission,
        world=limits,
        behaviors=found if found.declared else None,
        max_findings=limit,
    )
    shown = report.at_least(threshold)
    styled = use_color(color)
    text = render(shown, fmt, witness=witness, color=styled)
    typer.echo(text, nl=False, color=styled)
    for error in report.input_errors:
        error_line(str(error))
    # The exit code counts every finding, shown or not, and every unreadable input.
    raise typer.Exit(report.exit_code(strict))


def rules_listing(output_format: VerifyFormat) -> str:
    """Every rule of the registry: by area as text, or as JSON with its documentation."""
    rules = all_rules()
    if output_format is VerifyFormat.json:
        listing = [
            {
                "code": rule.code,
                "name": rule.name,
                "severity": rule.severity.value if rule.severity else None,
                "area": rule.area,
                "kind": rule.kind,
                "witness": rule.witness,
                "doc": rule.doc,
            }
            for rule in rules
        ]
        return json.dumps({"rules": listing}, indent=2) + "\n"
    if output_format is not VerifyFormat.text:
        raise AeroexecError(f"--list-rules prints text or json, not {output_format.value}")
    lines: list[str] = []
    area = None
    for rule in rules:
        if rule.area != area:
            area = rule.area
            lines += [""] if lines else []
            lines.append(area)
        severity = rule.severity.value if rule.severity else "varies"
        lines.append(f"  {rule.code}  {severity:<7}  {rule.name}")
    lines += ["", f"{len(rules)} rules; `aeroexec verify --explain CODE` documents one."]
    return "\n".join(lines) + "\n"
