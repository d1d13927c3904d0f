"""The faults the simulated vehicle models: one registry, read by the world files, the
simulator, `replay --inject`, `explore` and the docs.

Each kind has a name, what the simulator does when it strikes, the fault the vehicle then
reports (`VehicleState.fault`, "" for none) and its parameters, each with a unit, a
default and a range. World files and `--inject` write parameters in the same units
(`level` in percent, angles in degrees), so `low_battery:level=15` means what
`{kind: low_battery, level: 15}` means in a world file. `docs/whatif.md` renders
this table; a test keeps it true.

    for kind in FAULT_KINDS.values(): kind.name, kind.parameters
    parse_fault("wind_gust:speed=4,direction=90")  # -> FaultSpec
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from aeroexec.errors import InjectionError


@dataclass(frozen=True, slots=True)
class FaultParameter:
    name: str
    #: The unit it is written in (world files and `--inject`).
    unit: str
    default: float
    minimum: float
    maximum: float
    meaning: str
    #: Written value * scale = the simulator's value (percent -> fraction).
    scale: float = 1.0


@dataclass(frozen=True, slots=True)
class FaultKind:
    name: str
    #: What the simulated vehicle does when it strikes.
    effect: str
    #: The fault the vehicle reports while it lasts ("" : none, the world changed).
    reports: str
    parameters: tuple[FaultParameter, ...] = ()

    def parameter(self, name: str) -> FaultParameter | None:
        return next((p for p in self.parameters if p.name == name), None)


_DURATION = "how long it lasts"

#: Every fault kind, in the order tools list them. Never rename one: world files,
#: recordings (`injected`) and reports name them.
FAULT_KINDS: dict[str, FaultKind] = {
    kind.name: kind
    for kind in (
        FaultKind(
            "low_battery",
            "the battery's charge drops to `level` (it never rises); the battery belief "
            "says LOW below 20 %, and an empty battery forces a landing (battery_empty)",
            "",
            (FaultParameter("level", "%", 10.0, 0.0, 100.0, "the charge left", 0.01),),
        ),
        FaultKind(
            "stuck_motor",
            "a motor seizes: the vehicle stays where it is and refuses every command (for good)",
            "stuck_motor",
        ),
        FaultKind(
            "lost_link",
            "the link to the vehicle is lost for `duration`: every command is refused, the "
            "state the executive gets is the last one before the loss (with the fault) and "
            "the camera sends nothing; the vehicle keeps flying its last command, as an "
            "autopilot does before its own failsafe",
            "link_lost",
            (FaultParameter("duration", "s", 3.0, 0.1, 3600.0, _DURATION),),
        ),
        FaultKind(
            "lost_position",
            "the position estimate is lost for `duration` (a GPS or odometry outage): the "
            "vehicle lands where it is, as ArduCopter's EKF failsafe does, refuses position "
            "and velocity commands while it lasts, reports its last horizontal position "
            "(the altitude stays known), and the position belief is withdrawn; afterwards "
            "it keeps landing until it is commanded again",
            "position_lost",
            (FaultParameter("duration", "s", 5.0, 0.1, 3600.0, _DURATION),),
        ),
        FaultKind(
            "wind_gust",
            "a gust of `speed` toward `direction` for `duration` pushes the flying vehicle "
            "(its ground velocity is its own plus the wind's; the position controller "
            "does not know the wind and catches up afterwards)",
            "",
            (
                FaultParameter("speed", "m/s", 3.0, 0.0, 50.0, "the wind's speed"),
                FaultParameter(
                    "direction",
                    "deg",
                    0.0,
                    -360.0,
                    360.0,
                    "where it blows toward, counter-clockwise from +x (east)",
                ),
                FaultParameter("duration", "s", 2.0, 0.1, 3600.0, _DURATION),
            ),
        ),
    )
}

#: The kinds' names, in registry order.
KIND_NAMES: tuple[str, ...] = tuple(FAULT_KINDS)


def parameter_names() -> tuple[str, ...]:
    """Every parameter name of any kind (the keys a world file's failure may have)."""
    seen: dict[str, None] = {}
    for kind in FAULT_KINDS.values():
        for p in kind.parameters:
            seen.setdefault(p.name)
    return tuple(seen)


def kinds_with(name: str) -> tuple[str, ...]:
    """The kinds that take parameter `name`."""
    return tuple(k.name for k in FAULT_KINDS.values() if k.parameter(name) is not None)


def out_of_range(parameter: FaultParameter, value: float) -> str | None:
    """Why `value` (as written) is not a value of `parameter`, or None."""
    if not math.isfinite(value):
        return f"{parameter.name} must be a number, got {value}"
    if value < parameter.minimum:
        return f"{parameter.name} must be at least {parameter.minimum:g}, got {value:g}"
    if value > parameter.maximum:
        return f"{parameter.name} must be at most {parameter.maximum:g}, got {value:g}"
    return None


@dataclass(frozen=True, slots=True)
class FaultSpec:
    """A fault kind with the parameters given (as written, before scaling); the rest
    take their defaults."""

    kind: str
    given: tuple[tuple[str, float], ...] = ()

    def written(self, name: str) -> float:
        """The value of parameter `name` as written (given, else the default)."""
        for key, value in self.given:
            if key == name:
                return value
        parameter = FAULT_KINDS[self.kind].parameter(name)
        if parameter is None:
            raise KeyError(name)
        return parameter.default

    def values(self) -> dict[str, float]:
        """Every parameter of the kind, in the simulator's units."""
        kind = FAULT_KINDS[self.kind]
        return {p.name: self.written(p.name) * p.scale for p in kind.parameters}

    def __str__(self) -> str:
        if not self.given:
            return self.kind
        return self.kind + ":" + ",".join(f"{k}={_number(v)}" for k, v in self.given)


def _number(value: float) -> str:
    return f"{value:g}"


def parse_fault(text: str) -> FaultSpec:
    """`KIND` or `KIND:NAME=VALUE,...` (`low_battery:level=15`,
    `wind_gust:speed=4,direction=90,duration=1.5`); `InjectionError` naming what exists."""
    name, _, rest = text.partition(":")
    name = name.strip()
    kind = FAULT_KINDS.get(name)
    if kind is None:
        raise InjectionError(f"unknown fault kind {name!r} (known: {', '.join(KIND_NAMES)})")
    given: list[tuple[str, float]] = []
    if rest.strip():
        for item in rest.split(","):
            key, eq, raw = item.partition("=")
            key = key.strip()
            parameter = kind.parameter(key)
            if parameter is None:
                have = ", ".join(p.name for p in kind.parameters) or "none"
                raise InjectionError(
                    f"{kind.name} has no parameter {key!r} (its parameters: {have})"
                )
            if not eq:
                raise InjectionError(f"{kind.name}: write {key}=VALUE ({parameter.unit})")
            try:
                value = float(raw.strip().removesuffix(parameter.unit).strip())
            except ValueError:
                raise InjectionError(
                    f"{kind.name}: {key} must be a number ({parameter.unit}), got {raw.strip()!r}"
                ) from None
            problem = out_of_range(parameter, value)
            if problem is not None:
                raise InjectionError(f"{kind.name}: {problem}")
            if any(k == key for k, _ in given):
                raise InjectionError(f"{kind.name}: {key} is given twice")
            given.append((key, value))
    elif rest or text.endswith(":"):
        raise InjectionError(f"{kind.name}: nothing after ':' (write {kind.name} alone)")
    return FaultSpec(kind.name, tuple(given))


def markdown_table() -> str:
    """The registry as docs/whatif.md shows it (a test keeps the page true)."""
    lines = [
        "| kind | parameters (default) | what the simulator does | vehicle reports |",
        "| --- | --- | --- | --- |",
    ]
    for kind in FAULT_KINDS.values():
        parameters = "; ".join(
            f"`{p.name}` {p.unit} ({p.default:g}; {p.minimum:g} to {p.maximum:g}): {p.meaning}"
            for p in kind.parameters
        )
        reports = f"`{kind.reports}`" if kind.reports else "nothing"
        lines.append(f"| `{kind.name}` | {parameters or 'none'} | {kind.effect} | {reports} |")
    return "\n".join(lines) + "\n"
