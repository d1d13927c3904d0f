"""What every benchmark here shares: medians of CPU time, a fresh process's CPU time,
and the one-line report (figure, baseline, ratio, target).

Medians, not best-of-N: the best run of a shared machine measures its quietest moment,
not what a user gets. CPU time (user + system), not wall time: other jobs on the machine
stretch the wall clock, not the work done.
"""

from __future__ import annotations

import os
import resource
import statistics
import subprocess
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass


def cpu_median(action: Callable[[], object], repeat: int) -> float:
    """Median CPU seconds of `action()` in this process."""
    times = []
    for _ in range(repeat):
        start = time.process_time()
        action()
        times.append(time.process_time() - start)
    return statistics.median(times)


def child_cpu(command: Sequence[str], cwd: str | None = None) -> float:
    """CPU seconds (user + system) of one fresh process running `command`."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(
        list(command),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        check=False,
        cwd=cwd,
        env=os.environ.copy(),
    )
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def interleaved(actions: dict[str, Callable[[], float]], repeat: int) -> dict[str, float]:
    """Run each action (returning its own seconds) once per round, `repeat` rounds, so
    drift on the machine hits all of them alike; the median of each."""
    samples: dict[str, list[float]] = {name: [] for name in actions}
    for _ in range(repeat):
        for name, action in actions.items():
            samples[name].append(action())
    return {name: statistics.median(values) for name, values in samples.items()}


def timed(action: Callable[[], object]) -> Callable[[], float]:
    """`action` as a function returning the CPU seconds it took."""

    def run() -> float:
        start = time.process_time()
        action()
        return time.process_time() - start

    return run


@dataclass(frozen=True)
class Figure:
    """One line: what was measured, against what, the ratio and its target."""

    name: str
    value: float
    baseline: float
    baseline_name: str
    target: float
    unit: str = "s"
    #: "ratio" (value / baseline <= target), "max" (value <= target) or "min" (>= target)
    kind: str = "ratio"
    #: Why the target no longer holds (the line is still printed, and never fails).
    retired: str = ""

    @property
    def ratio(self) -> float:
        return self.value / self.baseline if self.baseline else float("inf")

    @property
    def ok(self) -> bool:
        if self.retired:
            return True
        if self.kind == "max":
            return self.value <= self.target
        if self.kind == "min":
            return self.value >= self.target
        return self.ratio <= self.target

    def line(self) -> str:
        def shown(x: float) -> str:
            if self.unit == "s":
                return f"{x * 1000:.1f} ms" if x < 10 else f"{x:.2f} s"
            if self.unit == " %" and abs(x) < 10:
                return f"{x:.2f}{self.unit}"
            return f"{x:,.0f}{self.unit}"

        if self.kind == "ratio":
            target = f"<= {self.target:g}x"
        elif self.kind == "max":
            target = f"<= {shown(self.target)}"
        else:
            target = f">= {shown(self.target)}"
        verdict = f"retired ({self.retired})" if self.retired else "ok" if self.ok else "MISSED"
        return (
            f"{self.name}: {shown(self.value)} | baseline {self.baseline_name} "
            f"{shown(self.baseline)} | ratio {self.ratio:.2f}x | target {target} {verdict}"
        )
