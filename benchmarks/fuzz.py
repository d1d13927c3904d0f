"""Benchmark: mission fuzzing (issue 27).

* throughput: generated missions per minute, recording off, properties on
  (`aeroexec:safety` and the executive's invariants), on the bundled catalog: the CPU time
  of `fuzz()` in this process, per mission, times the 2 cores the target is set for; and
  `--jobs 2` on replay's process pool, wall clock. Baseline: the same missions through
  `simulate()` alone (no Hypothesis, no properties, no invariants): the floor, what
  running them costs at all;
* shrinking: the most commands of any shrunk counterexample, for each class found on the
  bundled catalog and on the planted catalogs of tests/fixtures/verifier/rules;
* determinism: the same seed twice (once on two processes) gives the same findings, byte
  for byte (`findings.json`).

Medians of `--repeat` runs. Prints figure, baseline, ratio and target; exits 1 if a target
is missed.

    .venv/bin/python benchmarks/fuzz.py [--runs 300] [--repeat 3]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from collections.abc import Iterator, Sequence
from pathlib import Path

from figures import Figure

from aeroexec.catalog.paths import DEFAULT_CATALOG
from aeroexec.fuzz import search
from aeroexec.fuzz.campaign import Campaign, run_campaign
from aeroexec.fuzz.oracle import Bench, Target
from aeroexec.fuzz.search import Budget, ChunkResult, ChunkTask, fuzz
from aeroexec.fuzz.steps import Mission, commands
from aeroexec.mission.script import compile_mission
from aeroexec.mission.session import SessionConfig, simulate
from aeroexec.replay.executors import executor_for

REPO = Path(__file__).resolve().parent.parent
PLANTED = REPO / "tests" / "fixtures" / "verifier" / "rules"
MISSIONS_PER_MINUTE = 1000.0
MAX_COMMANDS = 10
CORES = 2


def record_missions(target: Target, runs: int, seed: int) -> list[Mission]:
    """The missions a search runs (to time them alone)."""
    seen: list[Mission] = []
    original = search.run_mission

    def spy(bench: Bench, mission: Mission, record: object = None):  # type: ignore[no-untyped-def]
        seen.append(mission)
        return original(bench, mission)

    search.run_mission = spy  # type: ignore[assignment]
    try:
        fuzz(target, Budget(runs=runs), seed_value=seed)
    finally:
        search.run_mission = original  # type: ignore[assignment]
    return seen


def bare(bench: Bench, missions: Sequence[Mission]) -> float:
    """CPU seconds of `simulate()` alone over `missions`."""
    start = time.process_time()
    for mission in missions:
        text, world = bench.texts(mission)
        config = SessionConfig(mission="mission.py", catalog=bench.target.catalog)
        simulate(
            config,
            catalog=bench.catalog,
            script=compile_mission(text, "mission.py"),
            world=(world, "world.yaml"),
        )
    return time.process_time() - start


def throughput(runs: int, repeat: int) -> list[Figure]:
    target = Target(str(DEFAULT_CATALOG))
    bench = Bench.of(target)
    per_mission: list[float] = []
    floor: list[float] = []
    walls: list[float] = []
    for seed in range(repeat):
        missions = record_missions(target, runs, seed)
        start = time.process_time()
        report = fuzz(target, Budget(runs=runs), seed_value=seed)
        per_mission.append((time.process_time() - start) / report.runs)
        floor.append(bare(bench, missions) / len(missions))
        with executor_for("local", CORES, CORES) as executor:

            def runner(tasks: Sequence[ChunkTask]) -> Iterator[ChunkResult]:
                for done in executor.run(tasks):
                    yield done.result

            start = time.monotonic()
            report = fuzz(target, Budget(runs=runs), seed_value=seed, runner=runner)
            walls.append(report.runs / (time.monotonic() - start) * 60)
    rate = CORES * 60 / statistics.median(per_mission)
    floor_rate = CORES * 60 / statistics.median(floor)
    return [
        Figure(
            "missions/minute, 2 cores (CPU)",
            rate,
            floor_rate,
            "simulate() alone",
            MISSIONS_PER_MINUTE,
            unit="/min",
            kind="min",
        ),
        Figure(
            "missions/minute, --jobs 2 (wall)",
            statistics.median(walls),
            floor_rate,
            "simulate() alone, 2 cores",
            MISSIONS_PER_MINUTE,
            unit="/min",
            kind="min",
        ),
    ]


def shrinking(runs: int) -> Figure:
    most = 0
    catalogs = [
        DEFAULT_CATALOG,
        *sorted(p for p in PLANTED.glob("AX*.yaml") if ".clean" not in p.name),
    ]
    for path in catalogs:
        target = Target(str(path), allow_unimplemented=True)
        try:
            report = fuzz(target, Budget(runs=runs), seed_value=0)
        except Exception:  # a planted catalog the executive refuses: nothing to shrink
            continue
        for finding in report.findings:
            most = max(most, len(commands(finding.mission)))
    return Figure(
        "commands of the longest shrunk counterexample",
        most,
        MAX_COMMANDS,
        "the target",
        MAX_COMMANDS,
        unit="",
        kind="max",
    )


def determinism(runs: int) -> Figure:
    outputs = []
    with tempfile.TemporaryDirectory() as scratch:
        for jobs in (1, 2):
            out = Path(scratch) / f"out{jobs}"
            campaign = Campaign(
                Target(str(DEFAULT_CATALOG)), Budget(runs=runs), out, seed=7, jobs=jobs
            )
            run_campaign(campaign)
            outputs.append((out / "findings.json").read_bytes())
    same = float(outputs[0] == outputs[1])
    return Figure(
        "same seed, same findings.json (1 = byte-identical)",
        same,
        1.0,
        "the target",
        1.0,
        unit="",
        kind="min",
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=300)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    figures = [*throughput(args.runs, args.repeat), shrinking(100), determinism(args.runs)]
    for figure in figures:
        print(figure.line())
    return 0 if all(f.ok for f in figures) else 1


if __name__ == "__main__":
    sys.exit(main())
