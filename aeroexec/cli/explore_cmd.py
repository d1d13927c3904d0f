"""`aeroexec explore REC...`: strike every fault at every transition of recorded missions."""

from __future__ import annotations

import contextlib
import sys
from enum import Enum
from pathlib import Path
from typing import Annotated

import typer

from aeroexec.catalog.loader import load_catalog
from aeroexec.cli.app import app, error_line, guarded
from aeroexec.cli.options import (
    apply_timeout,
    catalog_option,
    format_option,
    jobs_option,
    mission_option,
    output_dir_option,
    timeout_option,
)
from aeroexec.cli.project import (
    BehaviorsOption,
    DisablePluginOption,
    behavior_sources,
    discovered_behaviors,
    project,
)
from aeroexec.cli.spec import SpecOption, load_spec, with_safety
from aeroexec.errors import AeroexecError
from aeroexec.mission.script import load_mission
from aeroexec.replay.executors import LOCAL, executor_for
from aeroexec.replay.inputs import expand_inputs
from aeroexec.whatif import ExploreOptions, explore, parse_kinds, parse_offsets
from aeroexec.whatif import report as render

HELP = """Strike every fault the simulator models at every transition of recorded
missions (each activation, each end, each capability referenced or released, plus
--offsets) and report, per transition and fault, whether the system held, the mission
failed cleanly, or a property was violated (aeroexec:safety and --spec).

Each injection is a closed-loop replay (`aeroexec replay --inject`), run in parallel
with --jobs or --executor ray. Each violating run is written to --output-dir with the
one command line that makes it again; violations are grouped by cause (property,
transition kind, behavior). Recordings of `aeroexec fly` are explored in their simulated
twin (docs/whatif.md).

\b
Examples:
  aeroexec explore flight.mcap --trust-recording --output-dir whatif
  aeroexec explore runs/ -m mission.py --faults lost_link,wind_gust \\
      --offsets 0.5,2 --spec spec.yaml -j 2 --output-dir whatif -f junit

\b
Exit codes: 0 every injection held or failed cleanly; 1 a property was
            violated; 2 an input could not be read or a run not made.
"""


class ExploreFormat(str, Enum):
    text = "text"
    json = "json"
    junit = "junit"
    github = "github"


@app.command("explore", help=HELP)
@guarded
def explore_command(
    recordings: Annotated[
        list[str],
        typer.Argument(
            metavar="REC...",
            help="Recordings of `aeroexec run` or `aeroexec fly` (MCAP), directories or "
            "quoted globs.",
            show_default=False,
        ),
    ],
    output_dir: str = output_dir_option(
        "Where each violating run's recording is written (required)."
    ),
    faults: Annotated[
        str | None,
        typer.Option(
            "--faults",
            metavar="KINDS",
            help="Fault kinds to strike, comma-separated (default: every kind).",
            show_default=False,
        ),
    ] = None,
    offsets: Annotated[
        str | None,
        typer.Option(
            "--offsets",
            metavar="OFFSETS",
            help="Also strike this many seconds after each transition, comma-separated "
            "(0.5,2; negative: before).",
            show_default=False,
        ),
    ] = None,
    spec: SpecOption = None,
    catalog: Path | None = catalog_option("Catalog to run with (default: each recording's own)."),
    mission: Path | None = mission_option(
        "Run this mission script (your copy of the recorded one)."
    ),
    trust_recording: Annotated[
        bool,
        typer.Option(
            "--trust-recording",
            help="Run the mission script stored in each recording (it is code: only for "
            "recordings you trust). Without this or --mission, the recorded commands are "
            "replayed: they do not react to the faults.",
        ),
    ] = False,
    jobs: int = jobs_option(
        "Run this many injections at once, in worker processes (at most one per CPU)."
    ),
    executor: Annotated[
        str,
        typer.Option(
            "--executor",
            metavar="[local|ray|ray://HOST:PORT]",
            help="Where runs go: local (--jobs processes) or ray (Ray on this machine; "
            "needs aeroexec[ray]).",
            show_default=True,
        ),
    ] = LOCAL,
    behaviors: BehaviorsOption = None,
    disable_plugin: DisablePluginOption = None,
    timeout: float | None = timeout_option(
        "Stop a run's mission when it has run this long in wall-clock time (it fails at "
        "its file:line); also limits importing -b/--behaviors (exit 2). Default: none."
    ),
    output_format: ExploreFormat = format_option(
        ExploreFormat,
        "text: the table, causes and commands; json; junit (a test case per injection); "
        "github (workflow annotations).",
    ),
) -> None:
    apply_timeout(timeout)
    if output_dir is None:
        raise AeroexecError("--output-dir DIR is required: where violating runs are written")
    if executor.startswith("ray://"):
        raise AeroexecError("--output-dir is written where the runs go: not on a cluster (ray://)")
    kinds = parse_kinds(faults)
    moments = parse_offsets(offsets)
    specs = with_safety(spec)
    load_spec(specs)  # a bad property file is one error, before anything runs
    if catalog is not None:
        load_catalog(catalog)
    if mission is not None:
        load_mission(mission)
    sources = behavior_sources(behaviors, project(), disable_plugin)
    discovered_behaviors(sources)
    inputs = expand_inputs(recordings)
    for item in inputs:
        if item.error is not None:
            error_line(f"{item.path}: error: {item.error}")
    if any(item.error is not None for item in inputs):
        raise typer.Exit(2)
    paths = [item.path for item in inputs]
    replay_args = [
        *(arg for b in behaviors or () for arg in ("-b", b)),
        *(arg for d in disable_plugin or () for arg in ("--disable-plugin", d)),
    ]
    options = ExploreOptions(
        out_dir=output_dir,
        kinds=kinds,
        offsets=moments,
        spec=tuple(specs),
        catalog=str(catalog) if catalog is not None else None,
        mission=str(mission) if mission is not None else None,
        trust_recording=trust_recording,
        behaviors=sources,
        replay_args=tuple(replay_args),
    )
    # Workers fork before the progress bar's thread starts; until the report, stdout is
    # stderr (Ray prints its workers' deaths to stdout).
    with (
        executor_for(executor, jobs, None) as where,
        contextlib.redirect_stdout(sys.stderr),
        _Progress() as progress,
    ):
        result = explore(paths, options, where, on_planned=progress.start, on_done=progress.advance)
    if output_format is ExploreFormat.json:
        typer.echo(render.as_json(result), nl=False)
    elif output_format is ExploreFormat.junit:
        typer.echo(render.junit(result), nl=False)
    elif output_format is ExploreFormat.github:
        typer.echo(render.github(result), nl=False)
    else:
        typer.echo(render.text(result), nl=False)
    for run in result.errors:
        error_line(f"{run.run.recording}: error: {run.run.fault}@{run.run.when}: {run.error}")
    if result.errors:
        raise typer.Exit(2)
    if result.violated:
        raise typer.Exit(1)


class _Progress:
    """A bar on stderr, when it is a terminal: runs done of runs planned."""

    def __init__(self) -> None:
        self._progress = None
        self._task = None

    def __enter__(self) -> _Progress:
        return self

    def __exit__(self, *exc_info: object) -> None:
        if self._progress is not None:
            self._progress.stop()

    def start(self, total: int) -> None:
        if total < 1 or not sys.stderr.isatty():
            return
        from rich.console import Console
        from rich.progress import Progress

        self._progress = Progress(console=Console(stderr=True), transient=True)
        self._progress.start()
        self._task = self._progress.add_task("exploring", total=total)

    def advance(self, _done: object) -> None:
        if self._progress is not None and self._task is not None:
            self._progress.advance(self._task)
