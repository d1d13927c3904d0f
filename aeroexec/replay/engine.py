"""Replay recordings and diff each replay against its original.

    result = replay_recording("flight.mcap", ReplayOptions(catalog="new.yaml"))
    result.diff.differences      # what changed, per mission command
    # batches: aeroexec.replay.executors.replay_many (processes, Ray)

Mode: closed loop (re-simulate the mission) by default for simulated recordings
(metadata clock "sim"), open loop (recorded inputs into the executive) for the rest.
A recording cut short (a crash) is compared up to where it could be read, and the
report says so.
"""

from __future__ import annotations

import functools
import math
import os
import time
from collections.abc import Sequence
from contextlib import nullcontext
from dataclasses import dataclass, field, replace
from enum import Enum
from pathlib import Path
from typing import Any

from aeroexec.bags.replay import bag_recording
from aeroexec.bags.source import is_bag
from aeroexec.catalog.loader import load_catalog, parse_catalog, strict
from aeroexec.errors import (
    AeroexecError,
    CatalogError,
    InjectionError,
    Mark,
    RecordingError,
    one_line,
)
from aeroexec.executive.bus import BusObserver
from aeroexec.mission.script import load_mission
from aeroexec.plugins.discovery import BehaviorSet, BehaviorSources, discovered, standard_set
from aeroexec.plugins.manifest import CodeEntry, code_changes, code_manifest
from aeroexec.progress import ProgressFactory
from aeroexec.properties.check import VIOLATED
from aeroexec.recording.reader import attachment_place
from aeroexec.recording.tap import RecordTap
from aeroexec.recording.transitions import read_timeline
from aeroexec.replay.closedloop import ChosenCatalog, replay_closed
from aeroexec.replay.collect import RecordedRun, read_run
from aeroexec.replay.diff import DiffResult, Tolerance, diff_outcomes
from aeroexec.replay.inject import (
    Injection,
    ResolvedInjection,
    injected_metadata,
    recorded_injections,
    resolve_injections,
)
from aeroexec.replay.liveloop import is_live, replay_live
from aeroexec.replay.openloop import replay_open
from aeroexec.replay.outcome import NS_PER_S, RunOutcome
from aeroexec.replay.progress import ReplayedTime


class Mode(str, Enum):
    closed = "closed"
    open = "open"


@dataclass(frozen=True, slots=True)
class ReplayOptions:
    #: A catalog file to replay with (default: the recording's own catalog attachment).
    catalog: str | None = None
    #: None: closed for simulated recordings, open for the others.
    mode: Mode | None = None
    #: Write the replay to this MCAP file.
    output: str | None = None
    tolerance: Tolerance = field(default_factory=Tolerance)
    #: Where the behaviors come from (default: the standard library only). Plain data,
    #: so each worker process discovers the same set.
    behaviors: BehaviorSources | None = None
    #: Closed loop: run this mission script (the user's copy of the recorded one).
    mission: str | None = None
    #: Closed loop without `mission`: run the script stored in the recording (code from
    #: a file the user may have received from anyone: never by default).
    trust_recording: bool = False
    #: Closed loop: faults to strike (`--inject FAULT@WHEN`).
    injections: tuple[Injection, ...] = ()
    #: A flight's recording replayed in the simulator, which takes the vehicle's place
    #: from the state the flight started in (its simulated twin; closed loop).
    twin: bool = False
    #: Check each replay's recording against these properties (`--spec`): the name and
    #: text of each property file (`PropertySet.documents`), so that a worker anywhere
    #: loads the same set; the verdicts come back on `ReplayResult.properties`.
    properties: tuple[tuple[str, str], ...] = ()
    #: Keep the replay's clock to the wall clock, this many times as fast (`--speed`;
    #: None: as fast as it computes). Pacing only waits between ticks: the replay and
    #: its recording are the same at any speed.
    speed: float | None = None


@dataclass(frozen=True)
class SessionWatch:
    """Who watches a replay as it runs, here in this process (a live view: `replay
    --live`): `tap` sees the replay's recording as it is written (recorded to no file
    without `output`), `observers` observe its session (bus messages, and
    `session_started(executive)` and the other session hooks of
    `aeroexec.mission.session`: a viewer's abort stops the replay at a tick, and the
    session ends as `run`'s would). Not data: never sent to a worker process."""

    tap: RecordTap | None = None
    observers: tuple[BusObserver, ...] = ()


@dataclass(frozen=True, slots=True)
class ReplayResult:
    """One recording's replay: its diff against the original, or why it could not run."""

    recording: str
    mode: str | None = None
    catalog: str = ""
    #: True when the replay ran with the recording's own catalog attachment.
    catalog_recorded: bool = False
    diff: DiffResult | None = None
    error: str | None = None
    output: str | None = None
    notes: tuple[str, ...] = ()
    #: Behaviors whose code is not the code the recording ran (class or source changed).
    code_changes: tuple[str, ...] = ()
    #: With `ReplayOptions.properties`: the replay's verdicts, in their JSON form
    #: (`aeroexec.properties.report.recording_json`); None when not checked.
    properties: dict[str, Any] | None = None
    #: Wall-clock seconds the replay took (JUnit's `time`); not part of the result's
    #: value: equal results compare equal however long they took.
    seconds: float | None = field(default=None, compare=False)
    #: The faults struck (`FAULT@WHEN (at T s)`), a recording's own included.
    injected: tuple[str, ...] = ()
    #: What went wrong in the replay: refused activations and activations that ended in
    #: a failure (`#4 GO_TO_POINT ...: PROCESS_FAILURE (vehicle fault: link_lost)`), the
    #: mission's own failure.
    failures: tuple[str, ...] = ()

    @property
    def equal(self) -> bool:
        return self.error is None and self.diff is not None and self.diff.equal

    @property
    def checked(self) -> bool:
        """Whether the replay was checked against properties (`ReplayOptions.properties`)."""
        return self.properties is not None

    @property
    def violated(self) -> tuple[str, ...]:
        """The properties of severity error the replay violated (names)."""
        verdicts = self.properties["verdicts"] if self.properties is not None else ()
        return tuple(
            v["property"] for v in verdicts if v["status"] == VIOLATED and v["severity"] == "error"
        )

    def as_dict(self) -> dict[str, Any]:
        return {
            "recording": self.recording,
            "mode": self.mode,
            "catalog": self.catalog,
            "catalog_recorded": self.catalog_recorded,
            "equal": self.equal,
            "error": self.error,
            "output": self.output,
            "compared_commands": self.diff.compared if self.diff else 0,
            "differences": [d.as_dict() for d in self.diff.differences] if self.diff else [],
            "code_changes": list(self.code_changes),
            "notes": list(self.notes),
            "mission": self.diff.mission or None if self.diff else None,
            **(
                {"injected": list(self.injected), "failures": list(self.failures)}
                if self.injected
                else {}
            ),
        } | ({"properties": self.properties} if self.properties is not None else {})


def choose_mode(run: RecordedRun, requested: Mode | None) -> Mode:
    if requested is not None:
        return requested
    return Mode.closed if run.metadata.get("clock") == "sim" else Mode.open


def choose_catalog(run: RecordedRun, path: str | None) -> ChosenCatalog:
    if path is not None:
        catalog = load_catalog(path)
        return ChosenCatalog(catalog, catalog.text, Path(path).name)
    text = run.text("catalog.yaml")
    if text is None:
        raise CatalogError(
            "the recording has no catalog.yaml attachment: give one with --catalog",
            Mark(run.outcome.source),
        )
    name = run.metadata.get("catalog") or "catalog.yaml"
    catalog = strict(parse_catalog(text, attachment_place(run.outcome.source, "catalog.yaml")))
    return ChosenCatalog(catalog, text, name)


def replay_recording(
    path: str | os.PathLike[str],
    options: ReplayOptions,
    progress: ProgressFactory | None = None,
    watch: SessionWatch | None = None,
) -> ReplayResult:
    """Replay one recording and diff it against the original. Input problems raise
    `AeroexecError` (unreadable, not MCAP, no mission commands, bad catalog). `progress`
    is told how far the read of the recording is, then the replay (`replay.progress`);
    `watch` watches the replay as it runs (a live view)."""
    if is_bag(path):  # a ROS 1 bag: replayed through a temporary import (aeroexec.bags)
        return replay_bag(path, options, watch)
    watch = watch if watch is not None else SessionWatch()
    name = str(path)
    run = read_run(path, progress=progress)
    notes: list[str] = []
    horizon = None
    if run.outcome.intact_until_ns is not None:
        # Damaged in the middle: what follows the first damage may lack what was lost
        # there, so both runs are compared only before it.
        horizon = run.outcome.intact_until_ns
        run = read_run(path, horizon)
        notes.append(
            f"damaged recording ({run.outcome.problem}): compared the first "
            f"{horizon / NS_PER_S:.1f} s ({_commands(len(run.outcome.commands))}) only"
        )
    elif not run.outcome.complete:
        # Compare both runs up to (not including) the last instant the file holds: the
        # messages of that instant may be only partly there.
        horizon = run.outcome.end_ns
        run = read_run(path, horizon)
        shown = (horizon or 0) / NS_PER_S
        notes.append(
            f"incomplete recording ({run.outcome.problem}): compared the first {shown:.1f} s "
            f"({len(run.outcome.commands)} commands) only"
        )
    mode = choose_mode(run, options.mode)
    injected = _injections(path, run, options, mode)
    catalog = choose_catalog(run, options.catalog)
    behaviors = choose_behaviors(run, catalog, options.behaviors)
    span_ms = max(1, ((run.outcome.end_ns or 0) - (run.outcome.start_ns or 0)) // 1_000_000)
    bar = progress(f"replaying {Path(name).name}", span_ms) if progress else nullcontext(None)
    with bar as advance:
        timer = ReplayedTime(advance, span_ms) if advance is not None else None
        watchers: list[BusObserver] = list(watch.observers)
        if timer is not None:
            watchers.insert(0, timer)
        live = {"tap": watch.tap, "speed": options.speed}
        if mode is Mode.closed:
            mission = load_mission(options.mission) if options.mission is not None else None
            # A live flight cannot be flown again: its recorded vehicle stands in for it,
            # or, for its twin, the simulator from where the flight started.
            if options.twin:
                closed_loop = functools.partial(replay_closed, start=flight_start(path, run))
            elif is_live(run):
                closed_loop = functools.partial(replay_live, path)
            else:
                closed_loop = replay_closed
            replayed, how = closed_loop(
                run,
                catalog,
                behaviors,
                options.output,
                horizon,
                mission=mission,
                trust_recording=options.trust_recording,
                watchers=watchers,
                **live,
                **(_fault_arguments(injected) if injected else {}),
            )
        else:
            replayed, how = replay_open(
                path, run, catalog, behaviors, options.output, horizon, watchers, **live
            )
        if timer is not None:
            timer.finish()
    notes.extend(how)
    notes.extend(_never_struck(injected, replayed))
    changed = code_changes(run.code, code_manifest(behaviors, catalog.catalog).metadata())
    if not run.code:
        notes.append("the recording does not say which behavior code ran: code changes unknown")
    if behaviors.stand_ins:
        notes.append(f"stand-ins, as in the recording: {', '.join(behaviors.stand_ins)}")
    lines_of = _mission_lines(run, options, mode)
    diff = diff_outcomes(
        run.outcome,
        replayed,
        options.tolerance,
        base_name="the recording",
        new_name="the replay",
        compare_state=mode is Mode.closed,
        mission=lines_of[0],
        base_lines=lines_of[1],
    )
    notes.extend(diff.notes)
    return ReplayResult(
        recording=name,
        mode=mode.value,
        catalog=catalog.name if options.catalog is None else str(options.catalog),
        catalog_recorded=options.catalog is None,
        diff=diff,
        output=str(options.output) if options.output is not None else None,
        notes=tuple(notes),
        code_changes=changed,
        injected=tuple(r.describe() for r in injected),
        failures=run_failures(replayed, how) if injected else (),
    )


#: End events that are not a behavior's success (INTERRUPTED: stopped on purpose).
FAILURE_CODES = frozenset({"TIME_OUT", "WRONG_PROGRESS", "ASSUMPTION_CONFLICT", "PROCESS_FAILURE"})


def run_failures(outcome: RunOutcome, notes: Sequence[str]) -> tuple[str, ...]:
    """What went wrong in a run: refused activations, failed ends, a mission that raised."""
    found = []
    for command in outcome.commands:
        if command.activates and command.accepted is False:
            found.append(f"{command.label}: refused ({command.error})")
        elif command.end_code in FAILURE_CODES:
            detail = f" ({command.end_detail})" if command.end_detail else ""
            found.append(f"{command.label}: {command.end_code}{detail}")
    found.extend(n for n in notes if n.startswith("the replayed mission raised"))
    return tuple(found)


def _injections(
    path: str | os.PathLike[str], run: RecordedRun, options: ReplayOptions, mode: Mode
) -> tuple[ResolvedInjection, ...]:
    """The faults to strike: the recording's own (a replay's), then `--inject`'s,
    resolved from the recording. `InjectionError` when one cannot be."""
    recorded = recorded_injections(run.metadata, str(path))
    if not options.injections and not recorded:
        return ()
    if mode is not Mode.closed:
        if options.injections:
            raise InjectionError("--inject strikes faults into the simulator: closed loop only")
        return ()
    if is_live(run) and options.injections:
        raise InjectionError(
            "--inject on a flight's recording: a real flight cannot be flown again; "
            "explore it (aeroexec explore), which injects into its simulated twin"
        )
    start = run.outcome.start_ns or 0
    end = (run.outcome.end_ns or 0) - start
    return recorded + resolve_injections(options.injections, path, end)


def flight_start(path: str | os.PathLike[str], run: RecordedRun) -> tuple[float, float, float]:
    """Where a flight started (x, y, yaw in degrees: its first recorded vehicle state),
    for its simulated twin. `RecordingError` for a recording that is no flight's."""
    if not is_live(run):
        raise RecordingError(
            "a simulated twin is made of a flight's recording (aeroexec fly)", Mark(str(path))
        )
    state = read_timeline(path).first_state or {}
    position, yaw_rad = state.get("position"), state.get("yaw", 0.0)
    try:
        x, y = (float(v) for v in position[:2])  # type: ignore[index]
        yaw = math.degrees(float(yaw_rad))  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise RecordingError(
            "the flight has no vehicle state to start its simulated twin from", Mark(str(path))
        ) from None
    if not all(math.isfinite(v) for v in (x, y, yaw)):
        raise RecordingError("the flight's first vehicle state is not a position", Mark(str(path)))
    return (x, y, yaw)


def _never_struck(injected: tuple[ResolvedInjection, ...], replayed: RunOutcome) -> list[str]:
    """Notes for faults due after the replay had ended (the last transitions of a session)."""
    end = (replayed.end_ns or 0) - (replayed.start_ns or 0)
    return [
        f"{r.injection} was due at {r.due_ns / NS_PER_S:.3f} s, after the replay ended "
        f"({end / NS_PER_S:.3f} s): it never struck"
        for r in injected
        if r.due_ns > end
    ]


def _fault_arguments(injected: tuple[ResolvedInjection, ...]) -> dict[str, Any]:
    return {
        "faults": tuple(r.failure for r in injected),
        "faults_metadata": injected_metadata(injected),
    }


def _renamed(exc: AeroexecError, temp: Path, bag: str) -> AeroexecError:
    """The same error, naming the bag instead of the temporary recording."""
    if exc.mark is None or exc.mark.file != str(temp):
        return exc
    mark = replace(exc.mark, file=bag)
    return type(exc)(exc.message, mark)


def replay_bag(
    path: str | os.PathLike[str], options: ReplayOptions, watch: SessionWatch | None = None
) -> ReplayResult:
    """`replay_recording` for a bag (imported with the shipped mapping: Aerostack's for a
    ROS 1 bag, Aerostack2's for a ROS 2 one). An Aerostack2 flight has no catalog of its
    own: the replay runs its behavior timeline (the reconstructed activations, with the
    goals as arguments, each ending as recorded) against the `--catalog` given."""
    with bag_recording(path) as imported:
        if not imported.report.derived.get("mission/command"):
            known = (
                "the Aerostack mapping knows (behavior_event, list_of_active_behaviors, "
                "command topics)"
                if imported.report.ros_version == 1
                else "the Aerostack2 mapping knows (<ns>/<Behavior>/_behavior/behavior_status: "
                "rosbag2 records it only with --include-hidden-topics)"
            )
            raise RecordingError(
                f"no behavior commands to replay: the bag has none of the behavior topics "
                f"{known}; `aeroexec import --mapping` then replay the .mcap",
                Mark(str(path)),
            )
        try:
            result = replay_recording(imported.path, options, watch=watch)
        except AeroexecError as exc:
            raise _renamed(exc, imported.path, str(path)) from None
    notes = [f"imported from the bag: {note}" for note in imported.report.notes]
    reconstructed = (
        imported.report.reconstructed_activations + imported.report.reconstructed_inhibitions
    )
    if reconstructed:
        source = (
            "active-behavior list (bags hold no service calls)"
            if imported.report.ros_version == 1
            else "behavior status (Aerostack2 starts behaviors with action goals)"
        )
        notes.append(
            f"{reconstructed} of the recorded commands were reconstructed from the bag's {source}"
        )
    return replace(result, recording=str(path), notes=(*result.notes, *notes))


def _mission_lines(run: RecordedRun, options: ReplayOptions, mode: Mode) -> tuple[str, bool]:
    """Which script the replay's command lines are lines of: the user's (`--mission`),
    else the recorded one (whose lines the recording's commands carry, and a replay of
    them or of its script carries again). A replay of a replay names no script."""
    if mode is Mode.closed and options.mission is not None:
        return str(options.mission), False
    return _script(run), True


def choose_behaviors(
    run: RecordedRun, catalog: ChosenCatalog, sources: BehaviorSources | None
) -> BehaviorSet:
    """The behaviors to replay with: the current code (never code the recording
    carries). A behavior the recording ran as a stand-in is a stand-in again; any other
    catalog behavior without an implementation is a `BehaviorError`."""
    found = discovered(sources) if sources is not None else standard_set()
    recorded_stand_ins = [
        name
        for name, text in run.code.items()
        if CodeEntry.parse(text).stand_in and name not in found.implementations
    ]
    if recorded_stand_ins:
        found = found.with_stand_ins(recorded_stand_ins)
    return found.for_catalog(catalog.catalog)


def _commands(count: int) -> str:
    return f"{count} command{'s' if count != 1 else ''}"


def replay_file(
    path: str,
    options: ReplayOptions,
    progress: ProgressFactory | None = None,
    watch: SessionWatch | None = None,
) -> ReplayResult:
    """`replay_recording`, with input problems as a result (for batches and workers),
    and the time it took."""
    started = time.perf_counter()
    try:
        result = replay_recording(path, options, progress, watch)
    except AeroexecError as exc:
        result = ReplayResult(recording=path, error=_problem(path, exc), mode=_mode_name(options))
    return replace(result, seconds=time.perf_counter() - started)


def _problem(path: str, exc: AeroexecError) -> str:
    """The error, said after `PATH: error: ` (the line replay prints per recording):
    without the recording's name again, and an attachment's place as `attachment
    world.yaml:2:1`."""
    mark = exc.mark
    if mark is None:
        return str(exc)
    if mark.file == path:
        return one_line(exc.message)
    inside = attachment_place(path, "")
    if mark.file.startswith(inside):
        place = Mark(mark.file[len(inside) :], mark.line, mark.column)
        return one_line(f"attachment {place}: {exc.message}")
    return str(exc)


def _mode_name(options: ReplayOptions) -> str | None:
    return options.mode.value if options.mode is not None else None


def output_for(recording: str, out_dir: str) -> str:
    """Where `--output-dir` writes the replay of `recording` (a bag's replay is an MCAP)."""
    return str(Path(out_dir) / (Path(recording).stem + ".mcap"))


def diff_recordings(
    base: str | os.PathLike[str],
    new: str | os.PathLike[str],
    tolerance: Tolerance | None = None,
) -> DiffResult:
    """What changed from the recording `base` to the recording `new`. A recording cut
    short limits the comparison to the time both files cover."""
    runs = [read_run(base), read_run(new)]
    limits: list[int] = []
    why: list[str] = []
    for path, run in zip((base, new), runs, strict=True):
        outcome = run.outcome
        if outcome.intact_until_ns is not None:
            limits.append(outcome.intact_until_ns)
            why.append(f"{path} is damaged ({outcome.problem})")
        elif not outcome.complete and outcome.end_ns:
            limits.append(outcome.end_ns)
            why.append(f"{path} is incomplete ({outcome.problem})")
    notes: tuple[str, ...] = ()
    if limits:
        # Both runs are cut at the same instant, so neither is compared with the other
        # at a different time (the final state of one against a later one of the other).
        horizon = min(limits)
        runs = [read_run(base, horizon), read_run(new, horizon)]
        notes = (f"{'; '.join(why)}: compared both on their first {horizon / NS_PER_S:.1f} s only",)
    return diff_outcomes(
        runs[0].outcome,
        runs[1].outcome,
        tolerance,
        base_name=str(base),
        new_name=str(new),
        notes=notes,
        mission=_script(runs[1]),
        base_lines=_script(runs[0]) == _script(runs[1]),
    )


def _script(run: RecordedRun) -> str:
    """The mission script a recording's command lines are lines of ("" if none)."""
    recorded = run.metadata.get("mission") or ""
    return "" if recorded.startswith("(") else recorded  # "(mission/command stream)"
