"""What if: faults struck into recorded missions, at every transition.

* `plan` (plan.py): every fault kind at every transition (+ offsets) of recordings, the
  runs that decide them (one per distinct fault and instant);
* `explore` (explore.py): the runs, as closed-loop replays with `--inject` on replay's
  executors, judged held / failed cleanly / violated, the violations kept with the
  command that reproduces each;
* report.py: the table, the violations by cause, json, junit and github.
"""

from __future__ import annotations

from aeroexec.whatif.explore import ExploreOptions, ExploreResult, RunResult, explore
from aeroexec.whatif.plan import Plan, Probe, Run, parse_kinds, parse_offsets, plan

__all__ = [
    "ExploreOptions",
    "ExploreResult",
    "Plan",
    "Probe",
    "Run",
    "RunResult",
    "explore",
    "parse_kinds",
    "parse_offsets",
    "plan",
]
