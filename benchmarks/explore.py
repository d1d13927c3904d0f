"""Benchmark: what-if exploration (issue 26).

* explore of the thesis' Appendix C with every fault kind at every transition, on 2
  worker processes (`--jobs 2`): wall-clock median; target <= 60 s. Baseline: the floor
  of the same work, one plain recorded and checked replay of the recording per run,
  shared by the 2 workers (nothing injected, no table, no report);
* an injected replay as `replay --inject` runs it (WHEN resolved from the recording, a
  wind gust struck into a 10-minute patrol, which it rides out): simulated seconds per
  CPU second, median; target >= 500x real time. Baseline: the same replay with nothing
  injected;
* memory flat in the number of runs: the peak (tracemalloc) of a process that runs
  every injection itself (inline), with 3 offsets besides each transition (4x the runs)
  over the peak without; target <= 1.10x;
* reproduction: every violation explore reports on Appendix C, with the default catalog
  and with the planted ordering defect of tests/fixtures/whatif/land_conflict.yaml,
  replayed `--reproduce` times (default 100): the same bytes and the same violated
  properties every time; target: all of them.

Prints every figure with its baseline, ratio and target; exits 1 if a target is missed.

    .venv/bin/python benchmarks/explore.py [--repeat 3] [--reproduce 100]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import statistics
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

from figures import Figure, interleaved, timed
from replay import long_endurance_world, record_patrol

from aeroexec.mission.session import SessionConfig, simulate
from aeroexec.properties.spec import load_properties
from aeroexec.recording import open_recording
from aeroexec.replay.engine import ReplayOptions, ReplayResult, replay_recording
from aeroexec.replay.executors import InlineExecutor, ProcessExecutor
from aeroexec.replay.inject import Injection, parse_injection
from aeroexec.replay.tasks import ReplayTask, run_task
from aeroexec.vehicles.faults import KIND_NAMES, FaultSpec
from aeroexec.whatif import ExploreOptions, explore

ROOT = Path(__file__).resolve().parent.parent
MISSION = ROOT / "missions" / "appendix_c.py"
DEFECT = ROOT / "tests" / "fixtures" / "whatif" / "land_conflict.yaml"
EXPLORE_TARGET_S = 60.0
SPEED_TARGET = 500.0
MEMORY_RATIO_TARGET = 1.10
SAFETY = load_properties(["aeroexec:safety"]).documents


def wall(action: object) -> float:
    start = time.perf_counter()
    action()  # type: ignore[operator]
    return time.perf_counter() - start


def explore_wall(recording: Path, out: Path) -> tuple[float, int]:
    options = ExploreOptions(out_dir=str(out), trust_recording=True)
    start = time.perf_counter()
    with ProcessExecutor(2) as pool:
        result = explore([str(recording)], options, pool)
    return time.perf_counter() - start, len(result.results)


def plain_run(recording: Path, out: Path) -> None:
    """One run's floor: the recording replayed, recorded and checked, nothing injected."""
    options = ReplayOptions(trust_recording=True, output=str(out), properties=SAFETY)
    checked_replay(recording, options)


def checked_replay(recording: Path, options: ReplayOptions) -> ReplayResult:
    """A replay checked against its properties, as replay's executors run one."""
    return run_task(ReplayTask(0, str(recording), str(recording), options))


def duration_s(path: Path) -> float:
    survey = open_recording(path).survey()
    return ((survey.last_log_time_ns or 0) - (survey.first_log_time_ns or 0)) / 1e9


def driver_peak_kib(
    recording: Path, out: Path, kinds: tuple[str, ...], offsets: tuple[int, ...]
) -> tuple[float, int]:
    options = ExploreOptions(out_dir=str(out), kinds=kinds, offsets=offsets, trust_recording=True)
    tracemalloc.start()
    try:
        result = explore([str(recording)], options, InlineExecutor())
        return tracemalloc.get_traced_memory()[1] / 1024, len(result.results)
    finally:
        tracemalloc.stop()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3, help="timed runs; the median counts")
    parser.add_argument("--reproduce", type=int, default=100, help="replays per counterexample")
    args = parser.parse_args()
    repeat = max(1, args.repeat)
    figures: list[Figure] = []
    with tempfile.TemporaryDirectory(prefix="aeroexec-explore-bench-") as tmp:
        directory = Path(tmp)
        appendix_c = directory / "appendix_c.mcap"
        with contextlib.redirect_stdout(io.StringIO()):
            simulate(SessionConfig(mission=MISSION, record=appendix_c))

        # 1. explore of Appendix C, every fault at every transition, 2 workers.
        samples = [explore_wall(appendix_c, directory / f"explore-{i}") for i in range(repeat)]
        runs = samples[0][1]
        floor = statistics.median(
            wall(lambda: plain_run(appendix_c, directory / "plain.mcap")) for _ in range(5)
        )
        figures.append(
            Figure(
                f"explore Appendix C, {len(KIND_NAMES)} faults x every transition "
                f"({runs} runs, --jobs 2)",
                statistics.median(s[0] for s in samples),
                floor * runs / 2,
                f"{runs} plain replays / 2 workers",
                EXPLORE_TARGET_S,
                kind="max",
            )
        )

        # 2. an injected replay of a 10-minute patrol, in multiples of real time.
        world = long_endurance_world(directory)
        patrol = record_patrol(directory, "patrol-10", world)
        seconds = duration_s(patrol)
        gust = (parse_injection("wind_gust:speed=4,direction=45@activate:GO_TO_POINT#20"),)
        injected = ReplayOptions(trust_recording=True, injections=gust)
        plain = ReplayOptions(trust_recording=True)
        checked = replay_recording(patrol, injected)
        assert checked.injected and not checked.failures, checked.failures
        # CPU medians, interleaved (figures.py): other work on a shared machine stretches
        # the wall clock, not the work done.
        speeds = interleaved(
            {
                "injected": timed(lambda: replay_recording(patrol, injected)),
                "plain": timed(lambda: replay_recording(patrol, plain)),
            },
            max(3, repeat),
        )
        injected_wall, plain_wall = speeds["injected"], speeds["plain"]
        figures.append(
            Figure(
                f"injected replay of a {seconds / 60:.0f}-minute patrol (x real time, CPU)",
                seconds / injected_wall,
                seconds / plain_wall,
                "the plain replay",
                SPEED_TARGET,
                unit="x",
                kind="min",
            )
        )

        # 3. the driver's memory, few runs against many.
        few_kib, few = driver_peak_kib(appendix_c, directory / "few", KIND_NAMES, (0,))
        many_kib, many = driver_peak_kib(
            appendix_c,
            directory / "many",
            KIND_NAMES,
            (0, 500_000_000, 1_000_000_000, 2_000_000_000),
        )
        figures.append(
            Figure(
                f"explore peak, one process running {many} runs (tracemalloc)",
                many_kib * 1024,
                few_kib * 1024,
                f"{few} runs",
                MEMORY_RATIO_TARGET,
                unit=" B",
            )
        )

        # 4. every counterexample, of the default catalog and of a planted defect,
        # replayed again and again.
        defect = directory / "land_conflict.mcap"
        with contextlib.redirect_stdout(io.StringIO()):
            simulate(SessionConfig(mission=MISSION, record=defect, catalog=DEFECT))
        counterexamples = []
        for recording in (appendix_c, defect):
            found = explore(
                [str(recording)],
                ExploreOptions(
                    out_dir=str(directory / f"found-{recording.stem}"), trust_recording=True
                ),
            )
            counterexamples += [(recording, r) for r in found.results if r.outcome == "violated"]
        same = total = 0
        for recording, run in counterexamples:
            assert run.kept is not None
            original = Path(run.kept).read_bytes()
            options = ReplayOptions(
                trust_recording=True,
                injections=(Injection(FaultSpec(run.run.fault), run.run.when),),
                output=str(directory / "again.mcap"),
                properties=SAFETY,
            )
            for _ in range(max(1, args.reproduce)):
                again = checked_replay(recording, options)
                total += 1
                data = (directory / "again.mcap").read_bytes()
                same += data == original and again.violated == run.violated
        figures.append(
            Figure(
                f"counterexamples reproduced ({len(counterexamples)} x "
                f"{max(1, args.reproduce)} replays: same bytes, same violations)",
                same,
                total,
                "replays",
                total,
                unit="",
                kind="min",
            )
        )
    for figure in figures:
        print(figure.line())
    ok = all(f.ok for f in figures)
    print("all targets met" if ok else "some targets MISSED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
