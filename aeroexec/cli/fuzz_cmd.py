"""`aeroexec fuzz CATALOG`: generate missions, run them with properties on, shrink what
breaks and write each counterexample."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer

from aeroexec.cli.app import app, guarded
from aeroexec.cli.options import jobs_option, mission_option, quiet_option
from aeroexec.cli.project import (
    AllowUnimplementedOption,
    BehaviorsOption,
    DisablePluginOption,
    behavior_sources,
    project,
)
from aeroexec.cli.spec import SpecOption
from aeroexec.errors import FuzzError
from aeroexec.fuzz.campaign import Campaign, CampaignResult, run_campaign
from aeroexec.fuzz.oracle import SAFETY, Target
from aeroexec.fuzz.search import Budget
from aeroexec.fuzz.steps import commands
from aeroexec.progress import progress_bar
from aeroexec.replay.executors import LOCAL
from aeroexec.vehicles import world

NO_FAULTS = "none"


def fault_kinds(given: list[str] | None) -> tuple[str, ...] | None:
    """--faults: None (every kind) when not given; `none` alone: no faults."""
    # Comma-separated as `explore --faults` takes them, and repeatable.
    given = [kind.strip() for text in given or () for kind in text.split(",") if kind.strip()]
    if not given:
        return None
    if given == [NO_FAULTS]:
        return ()
    for kind in given:
        if kind not in world.FAILURE_KINDS:
            known = ", ".join((*world.FAILURE_KINDS, NO_FAULTS))
            raise FuzzError(f"--faults: unknown fault kind {kind!r} (known: {known})")
    return tuple(dict.fromkeys(given))


def _progress(description: str, total: int):  # type: ignore[no-untyped-def]
    """A bar on a terminal's stderr, however small the budget: a search takes seconds
    to minutes whatever its count."""
    return progress_bar(description, total, enabled=sys.stderr.isatty())


@app.command("fuzz")
@guarded
def fuzz(
    catalog: Path = typer.Argument(..., metavar="CATALOG", help="Behavior catalog (YAML)."),
    output_dir: Path = typer.Option(
        ...,
        "--output-dir",
        metavar="DIR",
        help="Where the findings, each counterexample (mission, world, recording, the "
        "violated property) and the database of past failures go.",
        show_default=False,
    ),
    mission: Path | None = mission_option(
        "Mutate this mission (reorder, drop, repeat commands, new argument values) "
        "instead of generating missions from scratch; it runs once to learn its commands."
    ),
    spec: SpecOption = None,
    faults: Annotated[
        list[str] | None,
        typer.Option(
            "--faults",
            metavar="KINDS",
            help="World fault kinds to inject, comma-separated (repeatable; default: every "
            f"kind the simulator knows: {', '.join(world.FAILURE_KINDS)}; {NO_FAULTS}: no "
            "faults).",
            show_default=False,
        ),
    ] = None,
    seed: int = typer.Option(
        0, "--seed", metavar="N", help="Seed of the search: the same seed, the same findings."
    ),
    budget: str = typer.Option(
        "1000",
        "--budget",
        metavar="BUDGET",
        help="How many missions to run (1000), or for how long (60s, 2m, 1h).",
    ),
    jobs: int = jobs_option("Search on this many processes (--executor local)."),
    executor: Annotated[
        str,
        typer.Option(
            "--executor",
            metavar="[local|ray|ray://HOST:PORT]",
            help="Where the search runs: local (--jobs processes), ray (Ray on this "
            "machine) or a Ray cluster (needs aeroexec[ray]).",
            show_default=True,
        ),
    ] = LOCAL,
    behaviors: BehaviorsOption = None,
    disable_plugin: DisablePluginOption = None,
    allow_unimplemented: AllowUnimplementedOption = False,
    quiet: bool = quiet_option(),
) -> None:
    """Generate missions for CATALOG, run them in simulation with properties on, and
    shrink each violation to a short mission that shows it.

    Example:

        aeroexec fuzz catalog.yaml --budget 60s --output-dir fuzz-out

    Each mission takes off (most of the time), then activates, inhibits and executes the
    catalog's behaviors with allowed argument values (boundaries included), waits, and
    meets world faults; it ends as a correct mission does: inhibits what it activated
    and lands with the catalog's landing behavior. Properties: aeroexec:safety and each
    --spec file, and the executive's own invariants (reference counts, an answer to
    every call). Each violated property gets its smallest mission, written to DIR as a
    mission script, its world file, its recording and the command lines that show the
    violation (`aeroexec run`, then `aeroexec check`). The missions that failed before
    (DIR/failures.json) run first.

    Exit code 0 when nothing was violated, 1 when something was, 2 when an input could
    not be used, 128+N when stopped by signal N (every failing mission found so far is
    in DIR/failures.json: the next run starts with them and writes them up).
    """
    try:
        parsed = Budget.parse(budget)
    except ValueError as exc:
        raise FuzzError(f"invalid value for --budget: {exc}") from None
    specs = tuple(dict.fromkeys((SAFETY, *(spec or ()))))
    target = Target(
        catalog=str(catalog),
        specs=specs,
        seed=0,
        behaviors=behavior_sources(behaviors, project(), disable_plugin),
        allow_unimplemented=allow_unimplemented,
        fault_kinds=fault_kinds(faults),
    )
    campaign = Campaign(
        target,
        parsed,
        output_dir,
        seed=seed,
        mission=mission,
        jobs=jobs,
        executor=executor,
        budget_text=budget,
    )
    result = run_campaign(campaign, progress=None if quiet else _progress)
    print_result(result, output_dir, quiet)
    if result.report.findings:
        raise typer.Exit(1)


def print_result(result: CampaignResult, output_dir: Path, quiet: bool) -> None:
    report = result.report
    if not quiet:
        for written in result.written:
            finding = written.finding
            count = len(commands(finding.mission))
            again = "" if written.reproduced else " (NOT reproduced from its files)"
            typer.echo(
                f"{output_dir / written.folder.name / 'mission.py'}: {finding.name}: "
                f"{finding.message} [{count} command{'' if count == 1 else 's'}]{again}"
            )
    replayed = f", {len(report.replayed)} from the database" if report.replayed else ""
    fixed = f", {report.fixed} past failures pass now" if report.fixed else ""
    typer.echo(
        f"{report.runs} missions run; {len(report.findings)} properties violated{replayed}{fixed}"
    )
    for error in report.errors:
        typer.echo(f"aeroexec fuzz: error: {error}", err=True)
