"""`aeroexec replay REC...`: re-run recorded missions with a new catalog or code version."""

from __future__ import annotations

import contextlib
import dataclasses
import os
import sys
import time
from enum import Enum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from aeroexec.catalog.loader import load_catalog
from aeroexec.cli.app import app, error_line, guarded
from aeroexec.cli.live import (
    LiveOption,
    PortOption,
    RerunPortOption,
    WaitViewerOption,
    check_live_options,
    live_speed,
    live_view,
)
from aeroexec.cli.options import (
    allow_remote_option,
    apply_timeout,
    catalog_option,
    choices,
    deprecated_option,
    format_option,
    jobs_option,
    mission_option,
    output_dir_option,
    output_option,
    replaced,
    timeout_option,
)
from aeroexec.cli.project import (
    BehaviorsOption,
    DisablePluginOption,
    behavior_sources,
    discovered_behaviors,
    project,
)
from aeroexec.cli.spec import (
    SpecOption,
    load_spec,
    verdicts_failed,
    verdicts_text,
    with_safety,
    with_verdicts_json,
    with_verdicts_junit,
)
from aeroexec.errors import AeroexecError, Mark, RecordingError
from aeroexec.inputs import is_regular_file
from aeroexec.mission.script import load_mission
from aeroexec.progress import ProgressFactory, progress_bar
from aeroexec.replay.diff import Tolerance
from aeroexec.replay.engine import Mode, ReplayOptions, ReplayResult, SessionWatch, output_for
from aeroexec.replay.executors import LOCAL, InlineExecutor, executor_for, replay_many
from aeroexec.replay.inject import Injection, parse_injection
from aeroexec.replay.inputs import expand_inputs
from aeroexec.replay.merge import shard_json
from aeroexec.replay.report import replay_json, replay_junit, replay_text, start_timing
from aeroexec.replay.shard import parse_shard, settings_of, slice_for
from aeroexec.replay.tasks import retried

if TYPE_CHECKING:
    from rich.progress import Progress

    from aeroexec.properties.spec import PropertySet
    from aeroexec.viz.live import LiveView

#: One recording at least this big gets bars for its read and replay (~2 s of work: a
#: 10-minute simulated patrol is ~1 MB and replays in ~0.4 s).
ONE_BIG_REPLAY_BYTES = 4 * 1024 * 1024


class OutputFormat(str, Enum):
    text = "text"
    json = "json"
    junit = "junit"


# Options `replay`, `diff` and `report merge` share, declared once so they read the same.
def report_format_option() -> Any:
    return format_option(OutputFormat, "text, json or junit (JUnit XML).")


ToleranceOption = Annotated[
    float,
    typer.Option(
        "--tolerance",
        metavar="SECONDS",
        help="Allowed drift of end-event times.",
        show_default=True,
    ),
]
PositionToleranceOption = Annotated[
    float,
    typer.Option(
        "--position-tolerance",
        metavar="METERS",
        help="Allowed drift of the final position.",
        show_default=True,
    ),
]


def tolerance_of(seconds: float, metres: float) -> Tolerance:
    try:
        return Tolerance(seconds, metres)
    except ValueError as exc:
        raise AeroexecError(str(exc)) from None


def _check_outputs(paths: list[str], output: str | None, out_dir: str | None) -> None:
    if output is not None and out_dir is not None:
        raise AeroexecError("give -o/--output or --output-dir, not both")
    if output is not None and len(paths) != 1:
        raise AeroexecError(f"-o/--output takes one recording, got {len(paths)}: use --output-dir")
    targets = [output] if output is not None else []
    if out_dir is not None:
        targets = [output_for(p, out_dir) for p in paths]
    if len(set(targets)) != len(targets):
        raise AeroexecError("--output-dir: two recordings would be written to the same file")
    sources = {Path(p).resolve() for p in paths if is_regular_file(p)}
    for target in targets:
        if Path(target).resolve() in sources:
            raise RecordingError("would overwrite a recording being replayed", Mark(target))
    if out_dir is not None:
        try:
            Path(out_dir).mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise RecordingError(f"cannot create: {exc.strerror or exc}", Mark(out_dir)) from None


def _one_big_replay(paths: list[str], executor: str) -> ProgressFactory | None:
    """For one big recording replayed here on a terminal: bars for its read and its
    replay (a bar over one file would sit at 0 % until the end)."""
    if executor != LOCAL or len(paths) != 1 or not sys.stderr.isatty():
        return None
    try:
        size = os.path.getsize(paths[0])
    except OSError:  # a URL, or a file the replay will report as unreadable
        return None
    if size < ONE_BIG_REPLAY_BYTES:
        return None
    return lambda description, total: progress_bar(description, total, enabled=True, unit="percent")


def _progress(total: int) -> Progress | None:
    """A rich progress bar on stderr when it is a terminal, else None."""
    if total < 1 or not sys.stderr.isatty():
        return None
    from rich.console import Console
    from rich.progress import Progress

    return Progress(console=Console(stderr=True), transient=True)


def _live(watching: _Watching | None, output: str | None) -> Any:
    """The live view around the replay (`--live`), or nothing."""
    if watching is None:
        return contextlib.nullcontext(None)
    return live_view(
        watching.live,
        port=watching.port,
        rerun_port=watching.rerun_port,
        wait_viewer=watching.wait_viewer,
        allow_remote=watching.allow_remote,
        abort_action="land",
        output=Path(output) if output is not None else None,
    )


def _watch(view: LiveView | None) -> SessionWatch | None:
    """What watches the replay: the live view, as the recording's tap and the session's
    observer (its abort, its wait for a viewer)."""
    return SessionWatch(tap=view, observers=(view,)) if view is not None else None


@app.command("replay")
@guarded
def replay(
    recordings: Annotated[
        list[str],
        typer.Argument(
            metavar="REC...",
            help="Recordings (.mcap, ROS 1 .bag, ROS 2 bags: a rosbag2 directory, a .db3, "
            "a ros2 .mcap), directories (every *.mcap and *.bag inside) or quoted globs.",
            show_default=False,
        ),
    ],
    catalog: Path | None = catalog_option(
        "Catalog to replay with (default: each recording's own)."
    ),
    mode: Annotated[
        Mode | None,
        typer.Option(
            "--mode",
            metavar=choices(Mode),
            help="closed: re-simulate the mission (default for simulated recordings); "
            "open: recorded inputs into the executive (default for live flights, bags).",
            show_default=False,
        ),
    ] = None,
    output: str | None = output_option("Record the replay to this MCAP file (one REC)."),
    output_dir: str | None = output_dir_option("Record each replay to DIR/<REC stem>.mcap."),
    out_dir: str | None = deprecated_option("--out-dir", instead="--output-dir", metavar="DIR"),
    check: Annotated[
        bool,
        typer.Option(
            "--check",
            help="Exit 1 when any replay differs from its recording (or, with --spec, "
            "violates a property).",
        ),
    ] = False,
    spec: SpecOption = None,
    jobs: int = jobs_option(
        "Replay this many recordings at once, in worker processes on this machine (at most "
        "one per CPU; --executor local)."
    ),
    behaviors: BehaviorsOption = None,
    timeout: float | None = timeout_option(
        "Closed loop: stop the mission when it has run this long in wall-clock time (for "
        "one that stops yielding: a loop, a sleep): it fails at its file:line, exit 1; "
        "also limits importing -b/--behaviors (exit 2). Default: no limit; 0: none."
    ),
    disable_plugin: DisablePluginOption = None,
    shard: Annotated[
        str | None,
        typer.Option(
            "--shard",
            metavar="K/N",
            show_default=False,
            help="Replay only shard K of N (by a hash of each recording's path: stable when "
            "recordings are added); merge the shards' --format json with "
            "`aeroexec report merge`.",
        ),
    ] = None,
    executor: Annotated[
        str,
        typer.Option(
            "--executor",
            metavar="[local|ray|ray://HOST:PORT]",
            help="Where replays run: local (--jobs processes), ray (Ray on this machine) or "
            "a Ray cluster (needs aeroexec[ray]).",
            show_default=True,
        ),
    ] = LOCAL,
    output_format: OutputFormat = report_format_option(),
    tolerance: ToleranceOption = 0.5,
    position_tolerance: PositionToleranceOption = 0.1,
    mission: Path | None = mission_option(
        "Closed loop: run this mission script (your copy of the recorded one; a note says "
        "when it differs)."
    ),
    trust_recording: Annotated[
        bool,
        typer.Option(
            "--trust-recording",
            help="Closed loop: run the mission script stored in the recording. It is code: "
            "only for recordings you trust. Without this or --mission, the recorded "
            "command stream is replayed and no code from the file runs.",
        ),
    ] = False,
    inject: Annotated[
        list[str] | None,
        typer.Option(
            "--inject",
            metavar="FAULT@WHEN",
            show_default=False,
            help="Closed loop: strike a simulator fault (low_battery:level=15, stuck_motor, "
            "lost_link, lost_position, wind_gust) at a time (12.5s) or a transition of the "
            "recording (end:TAKE_OFF, activate:GO_TO_POINT#2+0.5s) (repeatable); the replay "
            "is checked against --spec and aeroexec:safety (docs/whatif.md).",
        ),
    ] = None,
    live: LiveOption = False,
    port: PortOption = None,
    rerun_port: RerunPortOption = None,
    wait_viewer: WaitViewerOption = False,
    speed: Annotated[
        float | None,
        typer.Option(
            "--speed",
            metavar="FACTOR",
            help="Keep the replay's clock to the wall clock, FACTOR times as fast (default "
            "with --live: 1, the recording's own pace; without: as fast as it computes). "
            "The replay and its recording are the same at any speed.",
            show_default=False,
        ),
    ] = None,
    allow_remote: bool = allow_remote_option(
        "With --live: serve on every network interface, not only this machine (127.0.0.1)."
    ),
) -> None:
    """Replay recorded missions against a new catalog or code version and report, per
    mission command, what changed: accepted/rejected, preemptions, capabilities and
    processes, end events and their times, the final vehicle state.

    Closed loop re-simulates the mission with the recorded world and seed and the
    behaviors of today's code (-b/--behaviors, the project's [tool.aeroexec] behaviors,
    entry points, the standard library; never code a recording carries): it replays the
    recorded mission commands, or runs a mission script -- yours (--mission FILE), or the
    one stored in the recording if you trust it (--trust-recording); a recording is data
    anyone may send you, and its script is code. With the recording's own catalog and
    unchanged code the script replay reproduces the recording exactly (and -o writes the
    same bytes). Behaviors whose code differs from the recorded code are reported as
    "code changed". Open loop feeds the recorded commands, vehicle states and behavior
    outcomes to the executive and compares only its decisions.

    \b
    Examples:
      aeroexec replay flight.mcap --catalog catalog/new.yaml
      aeroexec replay flight.mcap --mission missions/appendix_c.py -o again.mcap
      aeroexec replay recordings/ -c new.yaml --check -j 4 -f junit > replay.xml
      aeroexec replay recordings/ --shard 2/4 --format json > shard-2.json
      aeroexec replay s3://flights/2024/ --executor ray://head:10001 --check

    With --spec, every replay is also checked against properties (docs/properties.md):
    with --check a replay passes only if they hold.

    With --inject, the replay strikes faults at moments of the recording and is checked
    against aeroexec:safety (and --spec); it is expected to differ from the recording, so
    --check fails it only for a violated property (docs/whatif.md):
      aeroexec replay flight.mcap --trust-recording --inject lost_link@end:TAKE_OFF --check

    With --live, one replay is served as it runs, paced to the recording's time
    (--speed), as `run --live` serves a run: a Foxglove WebSocket server (Foxglove,
    Lichtblick: ws://127.0.0.1:8765) and, with --rerun-port 9876, a Rerun gRPC stream
    (rerun rerun+http://127.0.0.1:9876/proxy) carry the replay's own recording; a viewer may
    call /abort_mission to stop it (docs/view.md). One recording, replayed here (not
    with -j or --executor ray): a viewer shows one session at a time.

    \b
      aeroexec replay flight.mcap --catalog new.yaml --live --wait-viewer

    Exit codes: 0 replayed (with --check: no differences); 1 with --check, some replay
    differs or violates a property; 2 an input could not be read (one line on stderr each).
    """
    apply_timeout(timeout)
    out_dir = replaced(output_dir, out_dir, new_name="--output-dir", old_name="--out-dir")
    # A JUnit report says when the run started (and checks SOURCE_DATE_EPOCH up front).
    timing = start_timing() if output_format is OutputFormat.junit else None
    started = time.perf_counter()
    if catalog is not None:
        load_catalog(catalog)  # a bad catalog is one error, not one per recording
    sources = behavior_sources(behaviors, project(), disable_plugin)
    discovered_behaviors(sources)  # so are bad behaviors (and the replays reuse what was found)
    if mission is not None:
        load_mission(mission)  # so is a bad mission script
    injections = tuple(parse_injection(text) for text in inject or ())  # so is a bad FAULT
    if injections and shard is not None:
        # A shard's settings do not carry the faults: `report merge` could not tell a
        # merged fault-free replay from an injected one.
        raise AeroexecError("--inject with --shard is not supported")
    if injections:
        spec = with_safety(spec)
    properties = load_spec(spec)  # so is a bad property file
    speed = live_speed(speed, live)
    check_live_options(live, port, rerun_port, wait_viewer)
    if allow_remote and not live:
        raise AeroexecError("--allow-remote is for --live: add --live")
    if live and (jobs > 1 or executor != LOCAL):
        # A live view is one session, served from this process.
        given = f"-j {jobs}" if jobs > 1 else f"--executor {executor}"
        raise AeroexecError(
            f"--live serves one replay as it runs here, in this process: not with {given}"
        )
    watching = _Watching(live, port, rerun_port, wait_viewer, allow_remote)
    _replay(
        _Run(
            recordings=recordings,
            catalog=catalog,
            mode=mode,
            output=output,
            out_dir=out_dir,
            check=check,
            jobs=jobs,
            sources=sources,
            shard=shard,
            executor=executor,
            output_format=output_format,
            tolerance=tolerance,
            position_tolerance=position_tolerance,
            mission=mission,
            trust_recording=trust_recording,
            timing=timing,
            started=started,
            properties=properties,
            injections=injections,
            speed=speed,
            watching=watching,
        )
    )


@dataclasses.dataclass(frozen=True)
class _Run:
    """What `replay` was asked, checked: the input of `_replay`."""

    recordings: list[str]
    catalog: Path | None
    mode: Mode | None
    output: str | None
    out_dir: str | None
    check: bool
    jobs: int
    sources: Any
    shard: str | None
    executor: str
    output_format: OutputFormat
    tolerance: float
    position_tolerance: float
    mission: Path | None
    trust_recording: bool
    timing: Any
    started: float
    properties: PropertySet | None
    injections: tuple[Injection, ...] = ()
    speed: float | None = None
    watching: _Watching | None = None


@dataclasses.dataclass(frozen=True)
class _Watching:
    """`--live` and its options, checked."""

    live: bool
    port: int | None
    rerun_port: int | None
    wait_viewer: bool
    allow_remote: bool


def _replay(run: _Run) -> None:
    (recordings, catalog, mode, output, out_dir, check, jobs, sources, shard, executor) = (
        run.recordings,
        run.catalog,
        run.mode,
        run.output,
        run.out_dir,
        run.check,
        run.jobs,
        run.sources,
        run.shard,
        run.executor,
    )
    output_format, tolerance, position_tolerance = (
        run.output_format,
        run.tolerance,
        run.position_tolerance,
    )
    mission, trust_recording, timing, started = (
        run.mission,
        run.trust_recording,
        run.timing,
        run.started,
    )
    properties = run.properties
    options = ReplayOptions(
        catalog=str(catalog) if catalog is not None else None,
        mode=mode,
        output=output,
        tolerance=tolerance_of(tolerance, position_tolerance),
        behaviors=sources,
        mission=str(mission) if mission is not None else None,
        trust_recording=trust_recording,
        # Checked where each replay runs (a scratch file there when it has no output).
        properties=properties.documents if properties is not None else (),
        injections=run.injections,
        speed=run.speed,
    )
    inputs = expand_inputs(recordings)
    part = None
    if shard is not None:
        part = slice_for([i.path for i in inputs], parse_shard(shard), settings_of(options))
        inputs = [inputs[p] for p in part.positions]
    paths = [i.path for i in inputs if i.error is None]
    watching = run.watching
    if watching is not None and watching.live and len(inputs) != 1:
        # Each replay is a session of its own, from time 0 on the same topics: one
        # viewer's timeline cannot hold two.
        raise AeroexecError(
            f"--live serves one replay as it runs: give one recording ({len(inputs)} given)"
        )
    _check_outputs(paths, output, out_dir)
    if executor.startswith("ray://") and (output is not None or out_dir is not None):
        raise AeroexecError(
            "-o/--output and --output-dir write where the replay runs: not on a cluster (ray://)"
        )
    # Workers start before the progress bar's thread (forking a threaded process is
    # unsafe). Until the report, stdout is stderr: Ray prints its workers' deaths to stdout.
    one_big = _one_big_replay(paths, executor)
    with (
        _live(watching, output) as view,
        InlineExecutor(one_big, _watch(view))
        if one_big is not None or not paths or view is not None
        else executor_for(executor, jobs, len(paths)) as where,
        contextlib.redirect_stdout(sys.stderr),
    ):
        progress = _progress(len(paths)) if one_big is None else None
        if progress is None:
            done = replay_many(paths, options, out_dir=out_dir, executor=where)
        else:
            with progress:
                task = progress.add_task("replaying", total=len(paths))
                done = replay_many(
                    paths,
                    options,
                    out_dir=out_dir,
                    executor=where,
                    on_done=lambda _result: progress.advance(task),
                )
    by_path = iter(done)
    results = [
        ReplayResult(recording=i.path, error=i.error) if i.error else next(by_path) for i in inputs
    ]
    for result in results:
        if result.error is not None:
            error_line(f"{result.recording}: error: {result.error}")
    again = retried(results)
    if again:
        error_line(f"note: retried after a worker failure: {', '.join(again)}")
    checked = [r.properties for r in results if r.properties is not None]
    if output_format is OutputFormat.json:
        document = replay_json(results) if part is None else shard_json(results, part)
        typer.echo(with_verdicts_json(document, checked) if properties is not None else document)
    elif output_format is OutputFormat.junit:
        document = replay_junit(results, timing=timing, seconds=time.perf_counter() - started)
        typer.echo(with_verdicts_junit(document, checked) if properties is not None else document)
    else:
        text = replay_text(results)
        if text:
            typer.echo(text)
        if properties is not None:
            typer.echo(verdicts_text(checked), nl=False)
    if any(r.error is not None for r in results):
        raise typer.Exit(2)
    # An injected replay is meant to differ: only what its properties say fails it.
    differs = not run.injections and not all(r.equal for r in results)
    if check and (verdicts_failed(checked) or differs):
        raise typer.Exit(1)
