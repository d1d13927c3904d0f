"""Replay recorded missions against a new catalog or code version, and diff outcomes.

* `replay_recording` (engine.py): closed loop (re-simulate the recorded
  mission, closedloop.py) or open loop (recorded inputs into the executive, openloop.py);
* `replay_many` (executors.py): a batch, in this process, in worker processes or on Ray
  (ray_executor.py), the same verdicts wherever; `--shard` slices (shard.py) and their
  merge (merge.py);
* `extract_outcome` (collect.py): the per-command summary of a recording, streaming;
* `diff_outcomes` (diff.py): what changed between two runs, command by command;
* report.py: the text, JSON and JUnit renderings used by `aeroexec replay` and `diff`.
"""

from __future__ import annotations

from aeroexec.replay.collect import extract_outcome, read_run
from aeroexec.replay.diff import Difference, DiffResult, Tolerance, diff_outcomes
from aeroexec.replay.engine import (
    Mode,
    ReplayOptions,
    ReplayResult,
    replay_file,
    replay_recording,
)
from aeroexec.replay.executors import replay_many
from aeroexec.replay.outcome import CommandOutcome, FinalState, RunOutcome, Transition

__all__ = [
    "CommandOutcome",
    "DiffResult",
    "Difference",
    "FinalState",
    "Mode",
    "ReplayOptions",
    "ReplayResult",
    "RunOutcome",
    "Tolerance",
    "Transition",
    "diff_outcomes",
    "extract_outcome",
    "read_run",
    "replay_file",
    "replay_many",
    "replay_recording",
]
