"""A whole `aeroexec fuzz` run: the database first, the search, the counterexamples.

    campaign = Campaign(target, Budget.parse("500"), output_dir=Path("out"), seed=1)
    result = run_campaign(campaign)          # result.written: one per violated property

The search runs on replay's executors (`--jobs N`: local processes; `--executor ray`),
started before any progress bar's thread (forking a threaded process is unsafe).
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

from aeroexec.errors import FuzzError, Mark
from aeroexec.fuzz.mutate import mission_steps
from aeroexec.fuzz.oracle import Bench, Target, run_mission
from aeroexec.fuzz.output import (
    DATABASE,
    Written,
    folder_name,
    read_database,
    remove_stale,
    write_counterexample,
    write_database,
    write_findings,
)
from aeroexec.fuzz.search import (
    CHUNK_RUNS,
    Budget,
    ChunkResult,
    ChunkTask,
    Finding,
    FuzzReport,
    fuzz,
)
from aeroexec.interrupts import Interrupted
from aeroexec.progress import ProgressFactory
from aeroexec.replay.executors import LOCAL, executor_for


@dataclass(frozen=True)
class Campaign:
    target: Target
    budget: Budget
    output_dir: Path
    seed: int = 0
    #: The mission to mutate (`-m`); None: generate from scratch.
    mission: Path | None = None
    jobs: int = 1
    executor: str = LOCAL
    #: The budget as the user wrote it (findings.json says it).
    budget_text: str = ""


@dataclass(frozen=True)
class CampaignResult:
    report: FuzzReport
    written: tuple[Written, ...]


def run_campaign(campaign: Campaign, progress: ProgressFactory | None = None) -> CampaignResult:
    target = campaign.target
    bench = Bench.of(target)
    run_mission(bench, ())  # inputs a mission cannot run with fail here, once, at once
    origin = mission_steps(bench, campaign.mission) if campaign.mission is not None else ()
    out = campaign.output_dir
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise FuzzError(f"cannot create this directory: {exc.strerror}", Mark(str(out))) from None
    database = read_database(out, target.catalog)
    budget = campaign.budget
    chunks = -(-budget.runs // CHUNK_RUNS) if budget.runs is not None else max(1, campaign.jobs)
    with executor_for(campaign.executor, campaign.jobs, chunks) as executor:

        def runner(tasks: Sequence[ChunkTask]) -> Iterator[ChunkResult]:
            for done in executor.run(tasks):
                yield done.result

        total = budget.runs if budget.runs is not None else round(budget.seconds or 0)
        with _bar(progress, total) as advance:
            started, shown = [time.monotonic()], [0]

            def on_chunk(result: ChunkResult) -> None:
                if budget.runs is not None:
                    advance(min(result.runs, CHUNK_RUNS))
                    return
                # A time budget's bar counts its seconds (the last chunk may overrun it).
                seconds = min(round(time.monotonic() - started[0]), total - shown[0])
                advance(seconds)
                shown[0] += seconds

            saved: list[list[Finding]] = []

            def on_found(findings: list[Finding]) -> None:
                # Saved as found: a signal, a crash or a killed CI job keeps every
                # failing mission, and the next run starts with them.
                write_database(out, target.catalog, findings)
                saved[:] = [findings]

            try:
                report = fuzz(
                    target,
                    budget,
                    seed_value=campaign.seed,
                    database=database,
                    origin=origin,
                    runner=runner,
                    waves=campaign.jobs,
                    on_chunk=on_chunk,
                    on_found=on_found,
                )
            except Interrupted as stop:
                if saved and saved[0]:
                    stop.notes.append(
                        f"the {len(saved[0])} failing mission(s) found so far are in "
                        f"{out / DATABASE}: the next run starts with them and writes them up"
                    )
                raise
    written = tuple(
        write_counterexample(bench, out / folder_name(i, f.name), f, campaign.seed)
        for i, f in enumerate(report.findings, 1)
    )
    write_findings(out, bench, report, written, seed=campaign.seed, budget=campaign.budget_text)
    write_database(out, target.catalog, report.findings)
    remove_stale(out, written)
    return CampaignResult(report, written)


@contextlib.contextmanager
def _bar(progress: ProgressFactory | None, total: int) -> Iterator:  # type: ignore[type-arg]
    if progress is None or total <= 0:
        yield lambda _n: None
        return
    with progress("fuzzing", total) as advance:
        yield advance
