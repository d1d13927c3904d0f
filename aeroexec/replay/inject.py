"""`FAULT@WHEN`: a fault of the simulator's registry, struck into a closed-loop replay at a
moment of the recording.

    injection = parse_injection("low_battery:level=15@end:TAKE_OFF")
    resolved = resolve_injections([injection], "flight.mcap", end_ns)
    failures = [r.failure for r in resolved]     # what the simulated vehicle gets

WHEN is resolved from the recording's transitions (`aeroexec.recording.transitions`, read
through the recording reader): replay and explore name the same moments the same way.
A replay records what was injected (metadata `injected`: fault, WHEN and the time it
resolved to), and a closed-loop replay of that recording strikes the same faults at the
same times again: they are part of the world it flew in.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass

from aeroexec.errors import InjectionError
from aeroexec.recording.transitions import (
    NS_PER_S,
    Moment,
    RecordedTransition,
    is_time,
    named,
    read_timeline,
    resolve_when,
)
from aeroexec.vehicles.faults import FaultSpec, parse_fault
from aeroexec.vehicles.world import ScheduledFailure

#: The session metadata key a replay records its injections under.
INJECTED = "injected"


@dataclass(frozen=True, slots=True)
class Injection:
    """A fault and the moment it strikes, as written. `due_ns`: already resolved (explore
    resolves once for all its runs); None: resolved from the recording replayed."""

    fault: FaultSpec
    when: str
    due_ns: int | None = None

    def __str__(self) -> str:
        return f"{self.fault}@{self.when}"


@dataclass(frozen=True, slots=True)
class ResolvedInjection:
    injection: Injection
    due_ns: int

    @property
    def failure(self) -> ScheduledFailure:
        return ScheduledFailure(
            self.injection.fault.kind, self.due_ns / NS_PER_S, **self.injection.fault.values()
        )

    def describe(self) -> str:
        return f"{self.injection} (at {self.due_ns / NS_PER_S:.3f} s)"

    def as_dict(self) -> dict[str, object]:
        return {
            "fault": str(self.injection.fault),
            "when": self.injection.when,
            "at_ns": self.due_ns,
        }


def parse_injection(text: str) -> Injection:
    """`FAULT@WHEN` (`lost_link:duration=2@activate:GO_TO_POINT#2`); `InjectionError`."""
    fault, at, when = text.rpartition("@")
    if not at or not fault.strip() or not when.strip():
        raise InjectionError(
            f"--inject {text!r}: expected FAULT@WHEN (low_battery:level=15@end:TAKE_OFF)"
        )
    return Injection(parse_fault(fault.strip()), when.strip())


def resolve_injections(
    injections: Iterable[Injection],
    recording: str | os.PathLike[str],
    end_ns: int,
    transitions: tuple[RecordedTransition, ...] | None = None,
) -> tuple[ResolvedInjection, ...]:
    """Each injection's time in the recording of length `end_ns`; its transitions are
    read once if one needs them, only as far as the last one named."""
    injections = list(injections)
    wanted = [named(i.when) for i in injections if i.due_ns is None and not is_time(i.when)]
    resolved = []
    for injection in injections:
        if injection.due_ns is not None:
            resolved.append(ResolvedInjection(injection, injection.due_ns))
            continue
        if transitions is None and not is_time(injection.when):
            transitions = read_timeline(recording, _until_found(wanted)).transitions
        moment: Moment = resolve_when(injection.when, transitions or (), end_ns, str(recording))
        resolved.append(ResolvedInjection(injection, moment.due_ns))
    return tuple(resolved)


def _until_found(
    wanted: list[tuple[str, str, int] | None],
) -> Callable[[list[RecordedTransition]], bool] | None:
    """Stop reading once every transition named has happened (a time, or a WHEN that
    does not parse, needs no transition; one that names none that exists reads all)."""
    if any(w is None for w in wanted):
        return None
    needed: dict[tuple[str, str], int] = {}
    for kind, name, n in (w for w in wanted if w is not None):
        needed[(kind, name)] = max(n, needed.get((kind, name), 0))
    looked = 0

    def enough(found: list[RecordedTransition]) -> bool:
        nonlocal looked
        for transition in found[looked:]:
            key = (transition.kind, transition.name)
            if needed.get(key, 0) and transition.occurrence >= needed[key]:
                del needed[key]
        looked = len(found)
        return not needed

    return enough


def injected_metadata(resolved: Iterable[ResolvedInjection]) -> dict[str, str]:
    """The metadata that records the injections (nothing when there are none)."""
    items = [r.as_dict() for r in resolved]
    return {INJECTED: json.dumps(items, separators=(",", ":"))} if items else {}


def recorded_injections(
    metadata: Mapping[str, str], recording: str
) -> tuple[ResolvedInjection, ...]:
    """The injections a recording says it was made with (a replay's); `InjectionError`
    when the record is malformed (a tampered file)."""
    text = metadata.get(INJECTED)
    if not text:
        return ()
    try:
        items = json.loads(text)
        found = tuple(
            ResolvedInjection(
                Injection(parse_fault(str(item["fault"])), str(item["when"])),
                int(item["at_ns"]),
            )
            for item in items
        )
    except (ValueError, TypeError, KeyError) as exc:
        raise InjectionError(
            f"{recording}: its '{INJECTED}' metadata is malformed ({exc})"
        ) from None
    if any(r.due_ns < 0 for r in found):
        raise InjectionError(f"{recording}: its '{INJECTED}' metadata has a negative time")
    return found
