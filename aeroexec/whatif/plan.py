"""What explore will run: every fault kind at every transition of every recording (plus
offsets), as replay tasks.

Each cell of the table (recording, transition + offset, fault) is one `Probe`. Probes
that strike the same fault at the same instant of the same recording are the same
closed-loop run (a capability handed over and taken back in one tick, an activation and
the end before it): they share one `Run`, so nothing is simulated twice.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from aeroexec.errors import InjectionError
from aeroexec.recording.transitions import (
    NS_PER_S,
    RecordedTransition,
    read_timeline,
    resolve_when,
)
from aeroexec.vehicles.faults import KIND_NAMES, FaultSpec

#: The transition kinds explore strikes at; a run shared by several transitions is named
#: after the first kind of this order (an end or an activation reads better than the
#: capability change that came with it).
TRANSITION_KINDS = ("end", "activate", "capability")


@dataclass(frozen=True, slots=True)
class Probe:
    """One cell: fault `fault` struck `offset_ns` after transition `transition`."""

    recording: str
    transition: RecordedTransition
    offset_ns: int
    fault: str
    #: Which run decides it (index into `Plan.runs`).
    run: int

    @property
    def when(self) -> str:
        """The WHEN that names this moment in `replay --inject` (its resolution gives the
        run's instant again)."""
        return self.transition.label + offset_text(self.offset_ns)

    @property
    def row(self) -> str:
        return f"{self.transition.label}{offset_text(self.offset_ns)}"


@dataclass(frozen=True, slots=True)
class Run:
    """One closed-loop replay: `fault` struck at `due_ns` into `recording`."""

    recording: str
    fault: str
    when: str
    due_ns: int


@dataclass(frozen=True, slots=True)
class Plan:
    probes: tuple[Probe, ...]
    runs: tuple[Run, ...]
    #: The transitions of each recording (what the rows are).
    transitions: dict[str, tuple[RecordedTransition, ...]]


def offset_text(offset_ns: int) -> str:
    if offset_ns == 0:
        return ""
    return f"{'+' if offset_ns > 0 else '-'}{abs(offset_ns) / NS_PER_S:g}s"


def parse_kinds(text: str | None) -> tuple[str, ...]:
    """`--faults KINDS`: comma-separated kinds of the registry (default: all)."""
    if text is None:
        return KIND_NAMES
    kinds = tuple(k.strip() for k in text.split(",") if k.strip())
    unknown = [k for k in kinds if k not in KIND_NAMES]
    if unknown or not kinds:
        raise InjectionError(
            f"--faults: unknown fault kind {unknown[0]!r} (known: {', '.join(KIND_NAMES)})"
            if unknown
            else f"--faults: no fault kind given (known: {', '.join(KIND_NAMES)})"
        )
    return tuple(dict.fromkeys(kinds))


def parse_offsets(text: str | None) -> tuple[int, ...]:
    """`--offsets OFFSETS`: seconds after each transition, comma-separated; 0 (the
    transition itself) is always tried."""
    offsets = [0]
    for item in (text or "").split(","):
        item = item.strip().removesuffix("s")
        if not item:
            continue
        try:
            seconds = float(item)
        except ValueError:
            raise InjectionError(f"--offsets: {item!r} is not a number of seconds") from None
        if not -3600 <= seconds <= 3600:
            raise InjectionError(f"--offsets: {seconds:g} s is more than an hour")
        offsets.append(round(seconds * NS_PER_S))
    return tuple(dict.fromkeys(offsets))


def plan(
    recordings: Sequence[str],
    kinds: Sequence[str],
    offsets: Sequence[int],
) -> Plan:
    """Every fault at every transition (+ offset) of every recording (each read once,
    through the recording reader). A transition plus a negative offset before the
    session began is left out."""
    probes: list[Probe] = []
    runs: list[Run] = []
    ranks: list[int] = []
    index: dict[tuple[str, str, int], int] = {}
    table: dict[str, tuple[RecordedTransition, ...]] = {}
    for recording in recordings:
        timeline = read_timeline(recording)
        transitions = timeline.transitions
        table[recording] = transitions
        for transition in transitions:
            if transition.kind not in TRANSITION_KINDS:
                continue
            for offset in offsets:
                when = transition.label + offset_text(offset)
                try:
                    due = resolve_when(when, transitions, timeline.end_ns, recording).due_ns
                except InjectionError:
                    continue  # before the session began: no such moment
                rank = TRANSITION_KINDS.index(transition.kind)
                for kind in kinds:
                    key = (recording, kind, due)
                    if key not in index:
                        index[key] = len(runs)
                        runs.append(Run(recording, kind, when, due))
                        ranks.append(rank)
                    elif rank < ranks[index[key]]:
                        runs[index[key]] = Run(recording, kind, when, due)
                        ranks[index[key]] = rank
                    probes.append(Probe(recording, transition, offset, kind, index[key]))
    return Plan(tuple(probes), tuple(runs), table)


def fault_of(run: Run) -> FaultSpec:
    """Explore strikes each kind with its documented defaults."""
    return FaultSpec(run.fault)
