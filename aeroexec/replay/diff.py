"""Compare two `RunOutcome`s command by command and say what changed, and why.

The runs are aligned by mission command: each command is identified by its kind and
behavior (or belief text), and the two sequences are matched (common prefix first,
then `difflib`) so that
commands present in only one run (the mission took another path) are reported as such
instead of shifting every comparison after them. Arguments are compared for the matched
pairs (a mission may compute them from beliefs).

Per matched command: accepted/rejected (and the error), preempted behaviors, end event
code, end time (the activation's duration, within `Tolerance.time_s`; for an INTERRUPTED
activation, who interrupted it instead: its time is that of another command), capability
and process transitions. Per run: the initiation's transitions and the final vehicle state
(position within `Tolerance.position_m`). A rejection that is new (or gone) is reported
alone: what follows from it (no processes, no end event) is its consequence.
"""

from __future__ import annotations

import difflib
import math
from collections import Counter
from dataclasses import dataclass
from typing import Any

from aeroexec.replay.outcome import (
    BEHAVIOR_COMMANDS,
    NS_PER_S,
    CommandOutcome,
    FinalState,
    RunOutcome,
    Transition,
    describe_arguments,
)

INTERRUPTED = "INTERRUPTED"

#: Difference kinds, in the order a reviewer reads them for one command.
KINDS = (
    "initialization",
    "only_in_base",
    "only_in_new",
    "arguments",
    "accepted",
    "error",
    "preemptions",
    "end_event",
    "end_time",
    "capabilities",
    "processes",
    "final_state",
)


@dataclass(frozen=True, slots=True)
class Tolerance:
    """How far two runs may drift and still count as equal."""

    time_s: float = 0.5
    position_m: float = 0.1

    def __post_init__(self) -> None:
        if not (self.time_s >= 0 and self.position_m >= 0):  # also refuses NaN
            raise ValueError("tolerances must be non-negative numbers")


@dataclass(frozen=True, slots=True)
class Difference:
    kind: str
    message: str
    #: The command's index (in the base run; in the new run for `only_in_new`), or None
    #: for run-level differences (initialization, final state).
    command: int | None = None
    label: str = ""
    base_index: int | None = None
    new_index: int | None = None
    #: The line of the mission script (`DiffResult.mission`) that made the command, when
    #: known.
    line: int | None = None

    def as_dict(self) -> dict[str, Any]:
        return {
            "command": self.command,
            "label": self.label,
            "kind": self.kind,
            "message": self.message,
            "base_index": self.base_index,
            "new_index": self.new_index,
            "line": self.line,
        }


@dataclass(frozen=True, slots=True)
class DiffResult:
    base: str
    new: str
    differences: tuple[Difference, ...]
    #: Commands matched between the two runs (and compared field by field).
    compared: int
    tolerance: Tolerance
    notes: tuple[str, ...] = ()
    #: The mission script the differences' lines are in ("" when unknown).
    mission: str = ""

    @property
    def equal(self) -> bool:
        return not self.differences

    @property
    def first_line(self) -> int | None:
        """The mission line of the first difference that has one (for CI annotations)."""
        return next((d.line for d in self.differences if d.line is not None), None)

    def as_dict(self) -> dict[str, Any]:
        return {
            "base": self.base,
            "new": self.new,
            "equal": self.equal,
            "compared_commands": self.compared,
            "tolerance": {"time_s": self.tolerance.time_s, "position_m": self.tolerance.position_m},
            "differences": [d.as_dict() for d in self.differences],
            "notes": list(self.notes),
            "mission": self.mission or None,
        }


def diff_outcomes(
    base: RunOutcome,
    new: RunOutcome,
    tolerance: Tolerance | None = None,
    *,
    base_name: str | None = None,
    new_name: str | None = None,
    compare_state: bool = True,
    notes: tuple[str, ...] = (),
    mission: str = "",
    base_lines: bool = False,
) -> DiffResult:
    """What changed from `base` to `new`. `compare_state=False` skips the final vehicle
    state (open-loop replay feeds the recorded state, so it cannot differ).

    `mission`: the script `new`'s command lines are lines of ("": unknown, no lines);
    `base_lines`: `base`'s are lines of it too (a replay of the recorded commands, or of
    the recorded script)."""
    lines = _Lines(bool(mission), base_lines)
    tol = tolerance or Tolerance()
    names = (base_name or base.source, new_name or new.source)
    out: list[Difference] = []
    compared = base.observed & new.observed
    _initialization(base, new, out, compared)
    matched = 0
    a = [c.key for c in base.commands]
    b = [c.key for c in new.commands]
    for tag, i1, i2, j1, j2 in align(a, b):
        if tag == "equal":
            for old, cur in zip(base.commands[i1:i2], new.commands[j1:j2], strict=True):
                matched += 1
                out.extend(_command(old, cur, tol, compared, lines.of(old, cur)))
            continue
        for old in base.commands[i1:i2]:
            out.append(
                _only(old, "only_in_base", names[0], lines.of(old, None), base_index=old.index)
            )
        for cur in new.commands[j1:j2]:
            out.append(
                _only(cur, "only_in_new", names[1], lines.of(None, cur), new_index=cur.index)
            )
    if compare_state:
        state = _final_state(base.final_state, new.final_state, tol)
        if state is not None:
            out.append(state)
    all_notes = list(notes)
    for kind in sorted((base.observed | new.observed) - compared):
        missing = base if kind not in base.observed else new
        all_notes.append(f"{missing.source} records no {kind} transitions: {kind} not compared")
    for run in (base, new):
        all_notes.extend(f"{run.source}: {note}" for note in run.notes)
    return DiffResult(names[0], names[1], tuple(out), matched, tol, tuple(all_notes), mission)


class _Lines:
    """Which run's command lines are lines of the mission script a report points at."""

    def __init__(self, new: bool, base: bool) -> None:
        self.new = new
        self.base = new and base

    def of(self, old: CommandOutcome | None, cur: CommandOutcome | None) -> int | None:
        if self.new and cur is not None and cur.line is not None:
            return cur.line
        if self.base and old is not None:
            return old.line
        return None


def align(
    a: list[tuple[str, str]], b: list[tuple[str, str]]
) -> list[tuple[str, int, int, int, int]]:
    """difflib opcodes, anchored on the common prefix: two runs of one mission agree
    until they diverge, so their first commands are matched first (a longest-block
    match could pair a run's start with the other's middle)."""
    prefix = 0
    while prefix < min(len(a), len(b)) and a[prefix] == b[prefix]:
        prefix += 1
    opcodes: list[tuple[str, int, int, int, int]] = []
    if prefix:
        opcodes.append(("equal", 0, prefix, 0, prefix))
    matcher = difflib.SequenceMatcher(None, a[prefix:], b[prefix:], autojunk=False)
    for tag, i1, i2, j1, j2 in matcher.get_opcodes():
        opcodes.append((tag, i1 + prefix, i2 + prefix, j1 + prefix, j2 + prefix))
    return opcodes


# -- one command ----------------------------------------------------------------------------
def _command(
    old: CommandOutcome,
    cur: CommandOutcome,
    tol: Tolerance,
    compared: frozenset[str],
    line: int | None,
) -> list[Difference]:
    out: list[Difference] = []
    label = old.label

    def add(kind: str, text: str) -> None:
        out.append(
            Difference(kind, f"{label} {text}", old.index, label, old.index, cur.index, line)
        )

    if old.arguments != cur.arguments:
        add(
            "arguments",
            f"now has arguments {describe_arguments(cur.arguments) or '(none)'} "
            f"(was {describe_arguments(old.arguments) or '(none)'})",
        )
    if old.command in BEHAVIOR_COMMANDS and (old.accepted is None) != (cur.accepted is None):
        # The mission API refused it before asking the executive (in one run only).
        if cur.accepted is None:
            add("accepted", "now refused by the mission API: the executive never saw it")
        else:
            state = "accepted" if cur.accepted else f"rejected: {cur.error}"
            add("accepted", f"now reaches the executive and is {state}")
        return out
    if old.accepted is not None and cur.accepted is not None and old.accepted != cur.accepted:
        if cur.accepted:
            add("accepted", f"now accepted (was rejected: {old.error})")
        else:
            add("accepted", f"now rejected: {cur.error}")
        return out
    if old.accepted is False and cur.accepted is False:
        if old.error != cur.error:
            add("error", f"rejected for another reason: {cur.error} (was: {old.error})")
        return out
    if old.preempted != cur.preempted:
        add("preemptions", _preemptions(old.preempted, cur.preempted))
    end = _end(old, cur, tol)
    if end is not None:
        add(*end)
    if "capabilities" in compared:
        capabilities = _transitions(old.capabilities, cur.capabilities, ("activates", "releases"))
        if capabilities:
            add("capabilities", f"capabilities: {capabilities}")
    if "processes" in compared:
        processes = _transitions(old.processes, cur.processes, ("starts", "stops"))
        if processes:
            add("processes", f"processes: {processes}")
    return out


def _only(
    command: CommandOutcome, kind: str, where: str, line: int | None, **index: int
) -> Difference:
    return Difference(
        kind,
        f"{command.label} only in {where}: the mission took another path",
        command.index,
        command.label,
        line=line,
        **index,
    )


def _preemptions(old: tuple[str, ...], cur: tuple[str, ...]) -> str:
    gained = [b for b in cur if b not in old]
    lost = [b for b in old if b not in cur]
    parts = []
    if gained:
        parts.append(f"now preempts {', '.join(gained)}")
    if lost:
        parts.append(f"no longer preempts {', '.join(lost)}")
    if not parts:
        parts.append(f"preempts in another order: {', '.join(cur)} (was {', '.join(old)})")
    return "; ".join(parts)


def _ending(command: CommandOutcome) -> str:
    if command.end_code is None or command.duration_ns is None:
        return "still active at the end"
    return f"{command.end_code} after {command.duration_ns / NS_PER_S:.1f} s"


def _end(old: CommandOutcome, cur: CommandOutcome, tol: Tolerance) -> tuple[str, str] | None:
    if not old.activates or old.accepted is False:
        return None
    if old.end_code != cur.end_code:
        detail = f": {cur.end_detail}" if cur.end_detail and cur.end_code else ""
        return ("end_event", f"now ends {_ending(cur)} (was {_ending(old)}){detail}")
    if old.end_code == INTERRUPTED:
        # Another command ended it (inhibit, preemption): when depends on that command,
        # which has its own line; what matters here is who interrupted it.
        if old.end_detail != cur.end_detail:
            return (
                "end_event",
                f"now ends {_ending(cur)}, {cur.end_detail or 'interrupted'} "
                f"(was {old.end_detail or 'interrupted'} after "
                f"{(old.duration_ns or 0) / NS_PER_S:.1f} s)",
            )
        return None
    if old.duration_ns is None or cur.duration_ns is None:
        return None
    drift = abs(cur.duration_ns - old.duration_ns) / NS_PER_S
    if drift > tol.time_s:
        return (
            "end_time",
            f"now ends {_ending(cur)} (was {old.duration_ns / NS_PER_S:.1f} s; "
            f"tolerance {tol.time_s:g} s)",
        )
    return None


def _transitions(
    old: tuple[Transition, ...], cur: tuple[Transition, ...], verbs: tuple[str, str]
) -> str:
    """'' when equal, else what is new and what is gone, e.g.
    'no longer starts droneYawPlanner; no longer stops droneYawPlanner'."""
    if old == cur:
        return ""
    before, after = Counter(old), Counter(cur)
    gained, lost = after - before, before - after

    def names(counter: Counter[Transition], up: bool) -> str:
        items = [t for t in dict.fromkeys((*cur, *old)) if t.up == up and counter[t]]
        return ", ".join(t.name + (f" (x{counter[t]})" if counter[t] > 1 else "") for t in items)

    parts = []
    for counter, prefix in ((gained, "now"), (lost, "no longer")):
        for up, verb in ((True, verbs[0]), (False, verbs[1])):
            listed = names(counter, up)
            if listed:
                parts.append(f"{prefix} {verb} {listed}")
    if not parts:
        shown = " ".join(str(t) for t in cur)
        return f"same changes in another order: {shown} (was {' '.join(str(t) for t in old)})"
    return "; ".join(parts)


# -- run level ------------------------------------------------------------------------------
def _initialization(
    base: RunOutcome, new: RunOutcome, out: list[Difference], compared: frozenset[str]
) -> None:
    for what, field, verbs in (
        ("capabilities", "initial_capabilities", ("activates", "releases")),
        ("processes", "initial_processes", ("starts", "stops")),
    ):
        if what not in compared:
            continue
        text = _transitions(getattr(base, field), getattr(new, field), verbs)
        if text:
            out.append(Difference("initialization", f"initialization {what}: {text}"))


def _final_state(
    old: FinalState | None, cur: FinalState | None, tol: Tolerance
) -> Difference | None:
    if old is None or cur is None:
        if old is cur:
            return None
        return Difference(
            "final_state",
            f"final vehicle state: {'now ' + cur.describe() if cur else 'now none'} "
            f"(was {old.describe() if old else 'none'})",
        )
    apart = math.dist(old.position, cur.position)
    if apart <= tol.position_m and old.flying == cur.flying:
        return None
    return Difference(
        "final_state",
        f"final vehicle state now {cur.describe()} (was {old.describe()}; "
        f"{apart:.2f} m apart, tolerance {tol.position_m:g} m)",
    )
