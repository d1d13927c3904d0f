"""Explore: strike every fault kind at every transition of recorded missions, and say which
injections the system holds up under.

    result = explore(["flight.mcap"], ExploreOptions(out_dir="whatif", trust_recording=True))
    result.outcome(probe)          # held | failed | violated | error
    result.groups()                # violations by cause

Each run is a closed-loop replay with `--inject` (`aeroexec.replay.engine`), run by
replay's executors (this process, worker processes, Ray) as a `ReplayTask` like any other
replay, recorded to a scratch file and checked against the properties where it ran. The
runs that violate a property are kept in the output directory, each with the one command
line that makes it again; the others are deleted as they finish, so the disk, like the
driver's memory (one small result per run), does not grow with what was held.

Outcomes: **violated** a property of severity error does not hold on the run; **failed**
no property is violated but the mission did not do what it set out to (a refused
activation, a behavior that ended in failure, the mission raised): it failed cleanly;
**held** neither; **error** the run could not be made (reported, exit 2).
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from aeroexec.errors import Mark, RecordingError
from aeroexec.interrupts import Interrupted
from aeroexec.plugins.discovery import BehaviorSources
from aeroexec.properties.spec import load_properties
from aeroexec.recording.reader import open_recording
from aeroexec.recording.schemas import PROFILE
from aeroexec.replay.engine import Mode, ReplayOptions, ReplayResult, replay_recording
from aeroexec.replay.executors import Executor, InlineExecutor
from aeroexec.replay.inject import Injection
from aeroexec.replay.tasks import ReplayTask
from aeroexec.vehicles.faults import KIND_NAMES, FaultSpec
from aeroexec.whatif.plan import Plan, Probe, Run, plan

HELD, FAILED, VIOLATED, ERROR = "held", "failed", "violated", "error"
OUTCOMES = (HELD, FAILED, VIOLATED, ERROR)


@dataclass(frozen=True)
class ExploreOptions:
    out_dir: str
    kinds: tuple[str, ...] = KIND_NAMES
    #: Offsets (ns) after each transition; 0 is the transition itself.
    offsets: tuple[int, ...] = (0,)
    #: Property files every run is checked against (aeroexec:safety among them).
    spec: tuple[str, ...] = ("aeroexec:safety",)
    catalog: str | None = None
    mission: str | None = None
    trust_recording: bool = False
    behaviors: BehaviorSources | None = None
    #: More options of `aeroexec replay` that select what the runs used (the behaviors:
    #: `-b ...`), for the command line that reproduces a violation.
    replay_args: tuple[str, ...] = ()


@dataclass(frozen=True, slots=True)
class RunResult:
    run: Run
    outcome: str
    violated: tuple[str, ...] = ()
    failures: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    error: str | None = None
    #: The violating run's recording in the output directory, and how to make it again.
    kept: str | None = None
    reproduce: str | None = None


@dataclass(frozen=True, slots=True)
class Group:
    """Violations with one cause: a property, a transition kind, a behavior."""

    property: str
    kind: str
    behavior: str
    probes: tuple[Probe, ...]


@dataclass(frozen=True)
class ExploreResult:
    plan: Plan
    results: tuple[RunResult, ...]
    options: ExploreOptions = field(repr=False)
    #: Twin -> the flight it stands for (recordings of `aeroexec fly`).
    flights: dict[str, str] = field(default_factory=dict)

    def result(self, probe: Probe) -> RunResult:
        return self.results[probe.run]

    def outcome(self, probe: Probe) -> str:
        return self.results[probe.run].outcome

    def counts(self) -> dict[str, int]:
        counts = dict.fromkeys(OUTCOMES, 0)
        for probe in self.plan.probes:
            counts[self.outcome(probe)] += 1
        return counts

    @property
    def violated(self) -> bool:
        return any(r.outcome == VIOLATED for r in self.results)

    @property
    def errors(self) -> tuple[RunResult, ...]:
        return tuple(r for r in self.results if r.outcome == ERROR)

    def groups(self) -> tuple[Group, ...]:
        """Violations by cause, in the order they were first met (table order)."""
        found: dict[tuple[str, str, str], list[Probe]] = {}
        for probe in self.plan.probes:
            for name in self.results[probe.run].violated:
                key = (name, probe.transition.kind, probe.transition.behavior)
                found.setdefault(key, []).append(probe)
        return tuple(Group(*key, tuple(probes)) for key, probes in found.items())


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.+-]+", "_", text).strip("_")


def kept_name(run: Run) -> str:
    """`appendix_c--stuck_motor--activate_ROTATE_1.mcap`: recording, fault, moment."""
    return f"{_slug(Path(run.recording).stem)}--{run.fault}--{_slug(run.when)}.mcap"


def reproduce_command(run: Run, kept: str, options: ExploreOptions) -> str:
    """The one command line that makes the violating run again (and exits 1)."""
    return shlex.join(
        [
            "aeroexec",
            "replay",
            run.recording,
            *(("-c", options.catalog) if options.catalog is not None else ()),
            *(("-m", options.mission) if options.mission is not None else ()),
            *(("--trust-recording",) if options.trust_recording else ()),
            *options.replay_args,
            *(arg for spec in options.spec for arg in ("--spec", spec)),
            "--inject",
            f"{run.fault}@{run.when}",
            "--check",
            "-o",
            kept,
        ]
    )


def _task(
    index: int,
    run: Run,
    scratch: Path,
    options: ExploreOptions,
    absolute: bool,
    documents: tuple[tuple[str, str], ...],
) -> ReplayTask:
    output = scratch / f"{index}.mcap"
    location = os.path.abspath(run.recording) if absolute else run.recording
    return ReplayTask(
        index,
        run.recording,
        location,
        ReplayOptions(
            catalog=options.catalog,
            mode=Mode.closed,
            output=str(output.resolve() if absolute else output),
            behaviors=options.behaviors,
            mission=options.mission,
            trust_recording=options.trust_recording,
            injections=(Injection(FaultSpec(run.fault), run.when, run.due_ns),),
            properties=documents,
        ),
    )


def _judged(run: Run, result: ReplayResult) -> RunResult:
    if result.error is not None:
        return RunResult(run, ERROR, error=result.error)
    if not result.checked:
        return RunResult(run, ERROR, error="the run was not checked against the properties")
    outcome = VIOLATED if result.violated else FAILED if result.failures else HELD
    never = tuple(n for n in result.notes if "never struck" in n)
    return RunResult(run, outcome, result.violated, result.failures, never)


def explore(
    recordings: Sequence[str],
    options: ExploreOptions,
    executor: Executor | None = None,
    on_planned: Callable[[int], None] | None = None,
    on_done: Callable[[RunResult], None] | None = None,
) -> ExploreResult:
    """Strike every fault kind of `options.kinds` at every transition (+ offsets) of each
    recording. `executor`: where the runs go (already started; default this process).
    `on_planned` is told how many runs there are, `on_done` each run as it finishes.
    Input problems with a recording (unreadable, not MCAP) raise `AeroexecError`."""
    out = Path(options.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    twins = {twin_of(path, options): path if is_flight(path) else None for path in recordings}
    the_plan = plan(list(twins), options.kinds, options.offsets)
    if on_planned is not None:
        on_planned(len(the_plan.runs))
    executor = executor if executor is not None else InlineExecutor()
    results: list[RunResult | None] = [None] * len(the_plan.runs)
    scratch = Path(tempfile.mkdtemp(prefix=".explore-", dir=out))
    try:
        absolute = executor.needs_absolute_paths
        # Read once here; each worker loads the same set from the documents' text.
        documents = load_properties(list(options.spec)).documents
        tasks = [
            _task(i, run, scratch, options, absolute, documents)
            for i, run in enumerate(the_plan.runs)
        ]
        for done in executor.run(tasks):
            run = the_plan.runs[done.index]
            judged = _judged(run, done.result)
            written = scratch / f"{done.index}.mcap"
            if judged.outcome == VIOLATED:
                kept = str(out / kept_name(run))
                os.replace(written, kept)
                judged = RunResult(
                    run,
                    judged.outcome,
                    judged.violated,
                    judged.failures,
                    judged.notes,
                    kept=kept,
                    reproduce=reproduce_command(run, kept, options),
                )
            else:
                written.unlink(missing_ok=True)
            results[done.index] = judged
            if on_done is not None:
                on_done(judged)
    except Interrupted as stop:
        # The runs in flight were finalized in the scratch folder, which goes now: say
        # what stays instead.
        stop.notes[:] = [n for n in stop.notes if str(scratch) not in n]
        finished = [r for r in results if r is not None]
        kept = sum(1 for r in finished if r.kept is not None)
        stop.notes.append(
            f"{len(finished)} of {len(results)} runs done, {kept} violating run(s) kept in {out}"
        )
        raise
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    missing = [i for i, r in enumerate(results) if r is None]
    if missing:  # an executor that loses a task is a bug, not a verdict
        raise RuntimeError(f"{executor.name} executor returned no result for run {missing[0]}")
    flights = {twin: flight for twin, flight in twins.items() if flight is not None}
    return ExploreResult(the_plan, tuple(r for r in results if r is not None), options, flights)


def is_flight(path: str) -> bool:
    """A recording of `aeroexec fly` (a live vehicle): explored in its simulated twin."""
    return open_recording(path).metadata.get(PROFILE, {}).get("vehicle") == "mavlink"


def twin_of(path: str, options: ExploreOptions) -> str:
    """The recording explore strikes faults into: `path` itself, or for a flight its
    simulated twin (made here, kept in the output directory: the violations' commands
    replay it). A twin that cannot be made is the flight's input error."""
    if not is_flight(path):
        return path
    twin = str(Path(options.out_dir) / f"{_slug(Path(path).stem)}--twin.mcap")
    result = replay_recording(
        path,
        ReplayOptions(
            catalog=options.catalog,
            mode=Mode.closed,
            output=twin,
            behaviors=options.behaviors,
            mission=options.mission,
            trust_recording=options.trust_recording,
            twin=True,
        ),
    )
    if result.error is not None:
        raise RecordingError(f"its simulated twin could not be made: {result.error}", Mark(path))
    return twin
