"""`aeroexec verify`: check catalogs (and the missions that use them) before flight."""

from __future__ import annotations

import dataclasses
import json
import shutil
from enum import Enum
from pathlib import Path

import typer

from aeroexec.catalog.model import Severity
from aeroexec.cli.app import app, error_line, guarded, say
from aeroexec.cli.options import (
    Color,
    apply_timeout,
    choices,
    color_option,
    format_option,
    mission_option,
    timeout_option,
    use_color,
    world_option,
)
from aeroexec.cli.project import (
    BehaviorsOption,
    DisablePluginOption,
    first,
    project,
    project_behaviors,
)
from aeroexec.cli.spec import SpecOption
from aeroexec.config import NO_VERIFY, ProjectConfig
from aeroexec.display import shown as shown_path
from aeroexec.errors import AeroexecError
from aeroexec.outputs import whole_file_or_none
from aeroexec.vehicles.world import load_world
from aeroexec.verifier import verify
from aeroexec.verifier.findings import InputError, Report
from aeroexec.verifier.fixes import fix_until_stable, unified_diff
from aeroexec.verifier.registry import all_rules, get, suggest_code
from aeroexec.verifier.report import render
from aeroexec.verifier.selection import RuleSelection, SelectionLayer, split_selectors
from aeroexec.verifier.signals import SignalUse

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
real behaviors (TAKE_OFF first, arguments).

Rules are chosen as with ruff: --select, --extend-select and --ignore take codes or
prefixes (AX7, AX71, AX711; ALL), on top of [tool.aeroexec.verify] in pyproject.toml
(select, extend-select, ignore, per-file-ignores). A comment on a finding's line
silences it: `# noqa: AX711` in a mission, `# aeroexec: ignore[AX401]` in a catalog.
Without CATALOG and --mission, the `catalogs` and `missions` the project lists there
(else its `catalog`) are checked: a bare `aeroexec verify` checks the whole project.

Property files given with --spec (docs/properties.md) are read and their signals
checked against each behavior catalog (AX75x: behaviors, capabilities and faults that
do not exist); a formula that does not parse is an input that cannot be read.

\b
Examples:
  aeroexec verify catalog/default.yaml
  aeroexec verify catalog/*.yaml --mission 'missions/*.py' --witness
  aeroexec verify config/mission/behavior_catalog.yaml  # 2020-2021 tasks
  aeroexec verify catalog/default.yaml -m mission.py --world worlds/field.yaml
  aeroexec verify catalog/default.yaml --format sarif > verify.sarif
  aeroexec verify catalog/default.yaml --spec spec.yaml
  aeroexec verify my-catalog.yaml -b mybehaviors
  aeroexec verify --select AX7 --ignore AX708 -m 'missions/*.py'
  aeroexec verify --statistics
  aeroexec verify --diff        # then --fix
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
        help="Catalog files (YAML); glob patterns allowed. Default: the catalogs of the "
        "project's [tool.aeroexec.verify], else its catalog.",
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
    spec: SpecOption = None,
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
    timeout: float | None = timeout_option(
        "Stop importing -b/--behaviors (and the project's) when it has run this long in "
        "wall-clock time: an error at its file:line, exit 2. Default: no limit."
    ),
    disable_plugin: DisablePluginOption = None,
    select: list[str] = typer.Option(
        None,
        "--select",
        metavar="CODE",
        help="Report only these rules: codes or prefixes (AX7, ALL), comma-separated; "
        "repeatable; replaces the project's select.",
        show_default=False,
    ),
    extend_select: list[str] = typer.Option(
        None,
        "--extend-select",
        metavar="CODE",
        help="Report these rules too (codes or prefixes, comma-separated; repeatable).",
        show_default=False,
    ),
    ignore: list[str] = typer.Option(
        None,
        "--ignore",
        metavar="CODE",
        help="Do not report these rules (codes or prefixes, comma-separated; repeatable); "
        "the most specific selector wins.",
        show_default=False,
    ),
    statistics: bool = typer.Option(
        False,
        "--statistics",
        help="Print how many findings each rule has (count, code, name) instead of the findings.",
    ),
    fix: bool = typer.Option(
        False,
        "--fix",
        help="Apply the mechanical fixes (AX803 misindented keys, AX401 one-sided "
        "preemption where unambiguous), then report what remains.",
    ),
    diff: bool = typer.Option(
        False,
        "--diff",
        help="Print the fixes --fix would apply as a unified diff, change nothing; exit 1 "
        "when there is one.",
    ),
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
    apply_timeout(timeout)
    if statistics and fmt not in ("text", "json"):
        raise AeroexecError(f"--statistics prints text or json, not {fmt}")
    settings = project()
    configured = settings.verify or NO_VERIFY
    # The project's paths are shown relative to the working directory, as given ones are.
    if not catalogs and not mission:
        mission = [shown_path(m) for m in configured.missions]
    if not catalogs:
        catalogs = [shown_path(c) for c in configured.catalogs]
    if not catalogs and settings.catalog is not None:
        catalogs = [str(settings.catalog)]
    if not catalogs:
        raise AeroexecError("no catalog given (try: aeroexec verify catalog.yaml)")
    selection = rule_selection(settings, select, extend_select, ignore)
    found = project_behaviors(behaviors, settings, disable_plugin)
    world_path = first(world, settings.world, None)
    limits = load_world(world_path) if world_path is not None else None
    # json and sarif are read by programs: every finding. Text and annotations are read
    # by people, who do not read a million lines of one rule.
    limit = max_findings if fmt in ("text", "github") and max_findings > 0 else None
    uses, spec_errors = signal_uses(spec or [])

    def run() -> Report:
        checked = verify(
            catalogs,
            mission,
            world=limits,
            behaviors=found if found.declared else None,
            signals=uses,
            selection=selection,
            max_findings=limit,
        )
        if spec_errors:
            checked = dataclasses.replace(
                checked, input_errors=(*checked.input_errors, *spec_errors)
            )
        return checked

    report = run()
    if fix or diff:
        # As ruff does: fixes again until none is left (a fix can make another
        # possible; fixes of the same lines wait for the next pass), in memory.
        fixed = fix_until_stable(run, report)
        if diff:
            shown = (unified_diff(f, fixed.before[f], after) for f, after in fixed.after.items())
            typer.echo("".join(shown), nl=False)
            say(
                "note",
                f"{_plural(fixed.applied, 'fix')} in {_plural(len(fixed.after), 'file')} would "
                f"apply ({_plural(fixed.passes, 'pass')}; --fix applies them)",
            )
            raise typer.Exit(1 if fixed.after else 0)
        for file, after in fixed.after.items():
            write_fixed(Path(file), after)
        report = fixed.report
        if fixed.after:
            say(
                "note",
                f"{_plural(fixed.applied, 'fix')} applied in {_plural(len(fixed.after), 'file')}",
            )
    shown = report.at_least(threshold)
    styled = use_color(color)
    if statistics:
        text = statistics_listing(shown, fmt)
    else:
        text = render(shown, fmt, witness=witness, color=styled)
    typer.echo(text, nl=False, color=styled)
    for error in report.input_errors:
        error_line(str(error))
    # The exit code counts every finding, shown or not, and every unreadable input.
    raise typer.Exit(report.exit_code(strict))


def signal_uses(specs: list[str]) -> tuple[list[SignalUse], list[InputError]]:
    """Each use of a signal in the property files `specs` (with its place), and the
    files that could not be read (an unknown signal or a syntax error is one of those:
    one line at its file:line:col, exit 2, the rest verified all the same)."""
    if not specs:
        return [], []
    from aeroexec.properties.spec import load_properties

    uses: list[SignalUse] = []
    errors: list[InputError] = []
    for spec in specs:
        try:
            properties = load_properties([spec], alone=True)
        except AeroexecError as exc:
            errors.append(InputError.of(exc, spec))
            continue
        for prop in properties.properties:
            uses.extend(SignalUse(name, mark) for name, mark in prop.formula.uses)
    return uses, errors


def _plural(count: int, word: str) -> str:
    plural = "es" if word.endswith(("x", "s")) else "s"
    return f"{count} {word}{'' if count == 1 else plural}"


def write_fixed(path: Path, content: bytes) -> None:
    """Replace a file by its fixed bytes, whole or not at all, keeping its mode."""
    with whole_file_or_none(path, AeroexecError) as temporary:
        temporary.write_bytes(content)
        shutil.copymode(path, temporary)


def rule_selection(
    settings: ProjectConfig,
    select: list[str] | None,
    extend_select: list[str] | None,
    ignore: list[str] | None,
) -> RuleSelection | None:
    """The project's [tool.aeroexec.verify] selection, then the command line's, as
    layers (None when neither says anything)."""
    configured = settings.verify or NO_VERIFY
    layers = []
    if configured.select is not None or configured.extend_select or configured.ignore:
        layers.append(
            SelectionLayer(
                split_selectors(configured.select) if configured.select is not None else None,
                split_selectors(configured.extend_select),
                split_selectors(configured.ignore),
            )
        )
    if select or extend_select or ignore:
        layers.append(
            SelectionLayer(
                split_selectors(select) if select else None,
                split_selectors(extend_select or ()),
                split_selectors(ignore or ()),
            )
        )
    per_file = {pattern: split_selectors(codes) for pattern, codes in configured.per_file_ignores}
    if not layers and not per_file:
        return None
    return RuleSelection(tuple(layers), per_file, settings.root)


def statistics_listing(report: Report, fmt: str) -> str:
    """How many findings each rule has, most first (ruff's --statistics)."""
    counts: dict[str, int] = {}
    for finding in report.findings:
        counts[finding.rule] = counts.get(finding.rule, 0) + 1
    ordered = sorted(counts.items(), key=lambda item: (-item[1], item[0]))
    names = {code: (rule.name if (rule := get(code)) else "") for code, _ in ordered}
    if fmt == "json":
        listing = [{"code": c, "name": names[c], "count": n} for c, n in ordered]
        return json.dumps(listing, indent=2) + "\n"
    width = max((len(str(n)) for _, n in ordered), default=1)
    return "".join(f"{n:>{width}}\t{c}\t{names[c]}\n" for c, n in ordered)


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
