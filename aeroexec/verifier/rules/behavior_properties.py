"""AX6xx: behavior properties — recurrent/timeout contradictions and argument specs."""

from __future__ import annotations

import math
from collections.abc import Iterator

from aeroexec.catalog.model import ArgumentKind, ArgumentSpec, Severity
from aeroexec.verifier.findings import Finding
from aeroexec.verifier.graphs import CatalogGraphs
from aeroexec.verifier.reach import describe_limits, travel_time
from aeroexec.verifier.registry import catalog_rule

W = Severity.WARNING

#: Argument names that mean "how long to keep doing it", in seconds.
DURATION_ARGUMENTS = ("duration",)


def _seconds(value: float) -> str:
    return f"{value:g} s"


@catalog_rule(
    "AX601",
    "timeout-on-recurrent",
    W,
    """A recurrent behavior (`recurrent: yes` or `category: recurrent`) is given a
    `timeout`. Recurrent behaviors run until they are inhibited; the executive arms no
    timeout for them, so the value is ignored. In flight: whoever wrote the timeout
    expects the behavior to stop by itself, and it never does. Fix: remove the timeout,
    or make the behavior goal-based if it really should end.""",
)
def timeout_on_recurrent(graphs: CatalogGraphs) -> Iterator[Finding]:
    for definition in graphs.behavior_defs:
        behavior = definition.item
        if behavior.recurrent and "timeout" in behavior.marks:
            value = f" {_seconds(behavior.timeout)}" if behavior.timeout else ""
            yield graphs.finding(
                "AX601",
                W,
                f"{behavior.name} is recurrent, so its timeout{value} is ignored: it runs "
                "until inhibited",
                behavior.mark_of("timeout"),
                (behavior.name,),
            )


@catalog_rule(
    "AX602",
    "timeout-shorter-than-duration",
    W,
    """A goal-based behavior accepts a `DURATION` argument whose largest allowed value
    exceeds the behavior's timeout (the thesis' WAIT and KEEP_HOVERING allow up to
    1000 s with a 15 s timeout). In flight: a long wait ends in TIME_OUT instead of
    GOAL_ACHIEVED. Fix: raise the timeout above the largest duration, or lower the
    bound.""",
)
def timeout_shorter_than_duration(graphs: CatalogGraphs) -> Iterator[Finding]:
    for definition in graphs.behavior_defs:
        behavior = definition.item
        if behavior.recurrent or behavior.timeout is None:
            continue
        for spec in behavior.arguments:
            if spec.name.casefold() not in DURATION_ARGUMENTS:
                continue
            if spec.kind is not ArgumentKind.RANGE or spec.maximum is None:
                continue
            if spec.maximum > behavior.timeout:
                yield graphs.finding(
                    "AX602",
                    W,
                    f"{behavior.name}: {spec.name} allows up to {_seconds(spec.maximum)} but "
                    f"the timeout is {_seconds(behavior.timeout)}: a longer wait ends in "
                    "TIME_OUT",
                    spec.mark if spec.mark.line else behavior.mark,
                    (behavior.name, spec.name),
                )


@catalog_rule(
    "AX603",
    "duplicate-argument",
    W,
    """A behavior declares two arguments whose names differ at most in letter case.
    Missions write argument names in any case (`coordinates=` for `COORDINATES`). In
    flight: the second declaration is never used — every value is checked against the
    first, whose range may not be the one meant. Fix: keep one declaration.""",
)
def duplicate_argument(graphs: CatalogGraphs) -> Iterator[Finding]:
    for definition in graphs.behavior_defs:
        behavior = definition.item
        seen: dict[str, int] = {}
        for spec in behavior.arguments:
            key = spec.name.casefold()
            if key in seen:
                line = seen[key]
                at = f" (first at line {line})" if line else ""
                yield graphs.finding(
                    "AX603",
                    W,
                    f"{behavior.name}: argument {spec.name} is declared twice{at}; the "
                    "second declaration is never used",
                    spec.mark if spec.mark.line else behavior.mark,
                    (behavior.name, spec.name),
                )
            else:
                seen[key] = spec.mark.line


def _farthest(spec: ArgumentSpec, kind: str, start: tuple[float, float, float]) -> list[float]:
    """Per axis, the largest distance a target the spec allows can be from where the
    behavior starts (the world's start for absolute targets, anywhere for relative)."""
    assert spec.minimum is not None and spec.maximum is not None
    origin = start if kind == "absolute" else (0.0, 0.0, 0.0)
    return [max(abs(spec.minimum - o), abs(spec.maximum - o)) for o in origin]


@catalog_rule(
    "AX604",
    "timeout-shorter-than-travel",
    W,
    """A goal-based behavior takes a destination (GO_TO_POINT's COORDINATES or
    RELATIVE_COORDINATES: the implementation declares which arguments are destinations)
    whose allowed range reaches farther than the vehicle can fly within the behavior's
    timeout, at the speed and acceleration limits of the world description (`verify
    --world`, default the built-in world; the same limits the simulator enforces). A
    30 s timeout with coordinates up to 100 m away needs at least 51 s at 2 m/s. In
    flight: a far target ends in TIME_OUT, not GOAL_ACHIEVED. Fix: raise the timeout
    above the longest flight, or narrow `allowed_values`.""",
)
def timeout_shorter_than_travel(graphs: CatalogGraphs) -> Iterator[Finding]:
    world = graphs.world
    for definition in graphs.behavior_defs:
        behavior = definition.item
        implementation = graphs.library.get(behavior.name)
        destinations = getattr(implementation, "destinations", None)
        if not destinations or behavior.recurrent or behavior.timeout is None:
            continue
        for spec in behavior.arguments:
            kind = destinations.get(spec.name.upper())
            if kind is None or spec.kind is not ArgumentKind.RANGE or spec.dimensions != 3:
                continue
            dx, dy, dz = _farthest(spec, kind, world.start)
            horizontal = math.hypot(dx, dy)
            seconds = travel_time(horizontal, dz, world.limits)
            if seconds <= behavior.timeout:
                continue
            where = "from the start" if kind == "absolute" else "away"
            yield graphs.finding(
                "AX604",
                W,
                f"{behavior.name}: {spec.name} allows targets {horizontal:.0f} m horizontally "
                f"and {dz:.0f} m vertically {where}, which takes at least {seconds:.0f} s at "
                f"{describe_limits(world.limits)} ({world.name} world), but the timeout is "
                f"{_seconds(behavior.timeout)}: a far target ends in TIME_OUT",
                spec.mark if spec.mark.line else behavior.mark,
                (behavior.name, spec.name),
            )
