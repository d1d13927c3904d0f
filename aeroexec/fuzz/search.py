"""The search: Hypothesis generates missions, runs each, and shrinks each violation.

The work is cut into chunks, each a Hypothesis run of `runs` missions from its own seed
(`chunk_seed(seed, index)`), with its own shrinking: a chunk is a plain `ChunkTask`, so
replay's executors run chunks in this process, in worker processes or on Ray, as they run
replays. Each chunk keeps, per violated property, the smallest mission that violated it
(fewest steps, then the text of its steps: a total order), and merging the chunks keeps
the smallest again, so the findings of a budget of runs are the same whatever ran them
and in whatever order they finished. A budget of time runs chunks until it is spent: its
findings depend on how fast the machine was, a budget of runs' do not.

Each property's violations raise their own exception class, so Hypothesis keeps and
shrinks one minimal example per property (`report_multiple_bugs`), and `target` is told
each property's robustness, the distance to its violation, to steer toward it.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

from hypothesis import HealthCheck, Phase, Verbosity, given, seed, settings, target
from hypothesis import strategies as st
from hypothesis.internal.conjecture import providers

from aeroexec.fuzz.oracle import Bench, Target, Violation, run_mission
from aeroexec.fuzz.steps import Mission, Step, step_from_dict
from aeroexec.fuzz.strategies import MAX_STEPS, missions, vocabulary
from aeroexec.progress import ProgressFactory

#: Missions per chunk: enough for Hypothesis to generate, target and shrink within one,
#: small enough that a time budget stops soon after it is spent.
CHUNK_RUNS = 100


@dataclass(frozen=True, slots=True)
class Finding:
    """The smallest mission found that violates `name`."""

    name: str
    message: str
    mission: Mission

    @property
    def key(self) -> tuple[int, str]:
        return (len(self.mission), steps_json(self.mission))


def steps_json(mission: Sequence[Step]) -> str:
    return json.dumps([s.as_dict() for s in mission], sort_keys=True, separators=(",", ":"))


def mission_from_json(data: Iterable[dict[str, Any]]) -> Mission:
    return tuple(step_from_dict(d) for d in data)


def keep_smallest(found: dict[str, Finding], candidates: Iterable[Finding]) -> None:
    for finding in candidates:
        held = found.get(finding.name)
        if held is None or finding.key < held.key:
            found[finding.name] = finding


def findings_of(violations: Iterable[Violation], mission: Mission) -> list[Finding]:
    return [Finding(v.name, v.message, mission) for v in violations]


#: At most this many missions are run to trim one finding (a dozen steps need fewer
#: than 80: a pass is one run a step, and each pass but the last removes one).
MAX_TRIM_RUNS = 200


def trimmed(bench: Bench, finding: Finding, max_runs: int = MAX_TRIM_RUNS) -> Finding:
    """`finding` with every step (command or fault) removed that its property does not
    need: each in turn, kept out when the mission without it still violates the same
    property, until no single removal does. Hypothesis shrinks a mission under the first
    property it violates, so the finding of a second property keeps the first one's
    steps; this pass shrinks under each property. A pure function of the finding."""
    mission, message = finding.mission, finding.message
    runs = 0
    removed = True
    while removed and runs < max_runs:
        removed = False
        index = 0
        while index < len(mission) and runs < max_runs:
            shorter = mission[:index] + mission[index + 1 :]
            runs += 1
            same = [v for v in run_mission(bench, shorter).violations if v.name == finding.name]
            if same:
                mission, message, removed = shorter, same[0].message, True
            else:
                index += 1
    return Finding(finding.name, message, mission)


#: A mission's seed for mutation (`-m`), or None to generate from scratch.
MutationSource = Callable[[Bench], "st.SearchStrategy[Mission]"]


@dataclass(frozen=True)
class ChunkTask:
    """Run `runs` missions against `target` from the chunk's own seed."""

    index: int
    target: Target
    seed: int
    runs: int
    max_steps: int = MAX_STEPS
    #: The mission to mutate (`-m`), as steps; empty: generate from scratch.
    origin: Mission = ()

    def run(self, progress: ProgressFactory | None = None) -> ChunkResult:
        return run_chunk(self)

    def lost(self, why: str) -> ChunkResult:
        return self.failed(f"chunk {self.index} not run: {why} (killed, or out of memory?)")

    def failed(self, text: str) -> ChunkResult:
        return ChunkResult(self.index, 0, (), error=text)

    def retried(self, result: ChunkResult, attempt: int) -> ChunkResult:
        return result  # a chunk is a pure function of its seed: a rerun finds the same


@dataclass(frozen=True)
class ChunkResult:
    index: int
    runs: int
    findings: tuple[Finding, ...]
    error: str | None = None


def chunk_seed(seed_value: int, index: int) -> int:
    return seed_value * 1_000_003 + index


class _Violated(Exception):
    """A mission violated a property (one subclass per property: Hypothesis shrinks each
    kind of failure on its own)."""


_classes: dict[str, type[_Violated]] = {}


def _violated(name: str) -> type[_Violated]:
    cls = _classes.get(name)
    if cls is None:
        cls = type(f"Violated[{name}]", (_Violated,), {})
        _classes[name] = cls
    return cls


def strategy_for(task: ChunkTask, bench: Bench) -> st.SearchStrategy[Mission]:
    words = vocabulary(bench.catalog, task.target.fault_kinds)
    if task.origin:
        from aeroexec.fuzz.mutate import mutations

        return mutations(task.origin, bench.catalog, words)
    return missions(bench.catalog, words, task.max_steps)


@contextmanager
def hermetic() -> Iterator[None]:
    """Hypothesis as a pure function of the seed: no constants read from the source of
    whatever local modules this process happens to have imported (Hypothesis mixes them
    into its draws, and caches them under `.hypothesis/` in the working directory), so a
    chunk draws the same missions in the command, a test, a worker or a Ray task."""
    saved = providers._get_local_constants
    providers._get_local_constants = _no_constants
    providers.CONSTANTS_CACHE.cache.clear()
    try:
        yield
    finally:
        providers._get_local_constants = saved
        providers.CONSTANTS_CACHE.cache.clear()


_NO_CONSTANTS = providers.Constants()


def _no_constants() -> providers.Constants:
    return _NO_CONSTANTS


def run_chunk(task: ChunkTask) -> ChunkResult:
    with hermetic():
        return _run_chunk(task)


def _run_chunk(task: ChunkTask) -> ChunkResult:
    bench = Bench.of(task.target)
    found: dict[str, Finding] = {}
    runs = 0

    def one(mission: Mission) -> None:
        nonlocal runs
        runs += 1
        judgement = run_mission(bench, mission)
        for name, value in sorted(judgement.robustness.items()):
            target(-value, label=name)
        if judgement.violations:
            keep_smallest(found, findings_of(judgement.violations, mission))
            first = judgement.violations[0]
            raise _violated(first.name)(first.message)

    test = settings(
        max_examples=task.runs,
        database=None,
        deadline=None,
        derandomize=False,
        phases=(Phase.generate, Phase.target, Phase.shrink),
        suppress_health_check=list(HealthCheck),
        report_multiple_bugs=True,
        verbosity=Verbosity.quiet,
        print_blob=False,
    )(seed(chunk_seed(task.seed, task.index))(given(strategy_for(task, bench))(one)))
    try:
        test()
    except _Violated:
        pass
    except BaseExceptionGroup as group:
        rest = group.subgroup(lambda e: not isinstance(e, _Violated))
        if rest is not None:
            raise rest.exceptions[0] from None
    return ChunkResult(task.index, runs, tuple(sorted(found.values(), key=lambda f: f.name)))


# -- the driver --------------------------------------------------------------------------


@dataclass(frozen=True)
class Budget:
    """Runs (missions) or seconds of wall-clock time."""

    runs: int | None = None
    seconds: float | None = None

    @staticmethod
    def parse(text: str) -> Budget:
        """`500` (runs), `60s`, `2m`, `1h` (time); ValueError with what is wrong."""
        spoken = text.strip().lower()
        units = {"s": 1.0, "m": 60.0, "h": 3600.0}
        if spoken and spoken[-1] in units:
            number = float(spoken[:-1])
            if not math.isfinite(number) or number <= 0:
                raise ValueError(f"a time budget must be positive, got {text!r}")
            return Budget(seconds=number * units[spoken[-1]])
        if not spoken.isdigit() or int(spoken) < 1:
            raise ValueError(
                f"expected a number of runs (500) or a time (60s, 2m, 1h), got {text!r}"
            )
        return Budget(runs=int(spoken))


@dataclass
class FuzzReport:
    findings: list[Finding]
    runs: int
    #: Findings of the database's missions that still fail (names).
    replayed: list[str] = field(default_factory=list)
    #: Database missions that pass now (fixed since).
    fixed: int = 0
    errors: list[str] = field(default_factory=list)


Runner = Callable[[Sequence[ChunkTask]], Iterator[ChunkResult]]


def inline(tasks: Sequence[ChunkTask]) -> Iterator[ChunkResult]:
    for task in tasks:
        yield task.run()


def fuzz(
    target_: Target,
    budget: Budget,
    *,
    seed_value: int = 0,
    database: Sequence[Mission] = (),
    origin: Mission = (),
    runner: Runner = inline,
    waves: int = 1,
    on_chunk: Callable[[ChunkResult], None] | None = None,
    on_found: Callable[[list[Finding]], None] | None = None,
    clock: Callable[[], float] = time.monotonic,
) -> FuzzReport:
    """Re-run the database's missions, then search. `waves`: how many chunks a time
    budget hands the runner at once (its parallelism). `on_found` is given every finding
    so far (untrimmed, by name) once the database has run and whenever a chunk finds
    something new or smaller, so a search stopped early loses nothing it found."""
    bench = Bench.of(target_)
    found: dict[str, Finding] = {}
    report = FuzzReport([], 0)
    for mission in database:
        judgement = run_mission(bench, mission)
        report.runs += 1
        if judgement.violations:
            keep_smallest(found, findings_of(judgement.violations, mission))
        else:
            report.fixed += 1
    report.replayed = sorted(found)
    if on_found is not None and database:
        on_found([found[name] for name in sorted(found)])

    def collect(results: Iterable[ChunkResult]) -> None:
        for result in results:
            report.runs += result.runs
            before = dict(found)
            keep_smallest(found, result.findings)
            if on_found is not None and found != before:
                on_found([found[name] for name in sorted(found)])
            if result.error:
                report.errors.append(result.error)
            if on_chunk is not None:
                on_chunk(result)

    def task(index: int, runs: int) -> ChunkTask:
        return ChunkTask(index, target_, seed_value, runs, origin=origin)

    if budget.runs is not None:
        size = min(CHUNK_RUNS, budget.runs)
        count = math.ceil(budget.runs / size)
        tasks = [task(i, min(size, budget.runs - i * size)) for i in range(count)]
        collect(runner(tasks))
    else:
        assert budget.seconds is not None
        end = clock() + budget.seconds
        index = 0
        while clock() < end:
            wave = [task(index + i, CHUNK_RUNS) for i in range(max(1, waves))]
            index += len(wave)
            collect(runner(wave))
    report.findings = [trimmed(bench, found[name]) for name in sorted(found)]
    return report
