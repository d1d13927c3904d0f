"""A generated mission as data, and the mission script and world file it is written as.

A mission is a tuple of steps: `Command`s (activate, inhibit, execute; a wait is an
execute of the catalog's waiting behavior) in the order the mission calls them, and
`Fault`s, world faults at a time of the session (the simulator injects them from the world
file, so the mission that runs under `aeroexec run -w world.yaml` is the one the fuzzer
ran). Every mission ends as a correct one would (`Ending`): it inhibits what it activated
and executes the catalog's landing behavior, so a finding is a defect of the catalog or
the executive, not a mission that forgot to land.
"""

from __future__ import annotations

import keyword
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from aeroexec.catalog.model import Catalog

EXECUTE = "execute"
ACTIVATE = "activate"
INHIBIT = "inhibit"
ACTIONS = (EXECUTE, ACTIVATE, INHIBIT)
#: The world file's line the faults replace (aeroexec/data/worlds/default.yaml).
NO_FAILURES = "failures: []"


@dataclass(frozen=True, slots=True)
class Command:
    action: str
    behavior: str
    #: (argument name as the catalog spells it, value), in the catalog's order.
    arguments: tuple[tuple[str, Any], ...] = ()

    def as_dict(self) -> dict[str, Any]:
        data: dict[str, Any] = {"action": self.action, "behavior": self.behavior}
        if self.arguments:
            data["arguments"] = [[name, value] for name, value in self.arguments]
        return data


@dataclass(frozen=True, slots=True)
class Fault:
    kind: str
    #: Simulated seconds from the session's start, in tenths (the executive's tick).
    at_ds: int

    @property
    def at_s(self) -> float:
        return self.at_ds / 10

    def as_dict(self) -> dict[str, Any]:
        return {"fault": self.kind, "at_s": self.at_s}


Step = Command | Fault
Mission = tuple[Step, ...]


def step_from_dict(data: dict[str, Any]) -> Step:
    """The inverse of `as_dict` (the failure database, a mutation's seed mission)."""
    if "fault" in data:
        return Fault(str(data["fault"]), round(float(data["at_s"]) * 10))
    arguments = tuple((str(n), _tuple_free(v)) for n, v in data.get("arguments", ()))
    return Command(str(data["action"]), str(data["behavior"]), arguments)


def _tuple_free(value: Any) -> Any:
    return list(value) if isinstance(value, tuple) else value


def commands(mission: Sequence[Step]) -> list[Command]:
    return [s for s in mission if isinstance(s, Command)]


def faults(mission: Sequence[Step]) -> list[Fault]:
    return sorted((s for s in mission if isinstance(s, Fault)), key=lambda f: (f.at_ds, f.kind))


def landing_behavior(catalog: Catalog) -> str | None:
    """The behavior a correct mission lands with: LAND, else the first non-recurrent
    behavior whose name starts with LAND (catalog order); None when there is none."""
    landing = catalog.behaviors.get("LAND")
    if landing is not None and not landing.recurrent:
        return "LAND"
    for name, behavior in catalog.behaviors.items():
        if name.startswith("LAND") and not behavior.recurrent:
            return name
    return None


@dataclass(frozen=True, slots=True)
class Ending:
    """What the mission does after its steps: inhibit, then land."""

    inhibit: tuple[str, ...]
    land: str | None

    def commands(self) -> tuple[Command, ...]:
        inhibits = tuple(Command(INHIBIT, name) for name in self.inhibit)
        return inhibits + ((Command(EXECUTE, self.land),) if self.land else ())


def ending_for(mission: Sequence[Step], catalog: Catalog) -> Ending:
    """Inhibit every behavior the mission activated (most recent first), then land."""
    activated: dict[str, None] = {}
    for command in commands(mission):
        if command.action == ACTIVATE:
            activated.pop(command.behavior, None)
            activated[command.behavior] = None
    return Ending(tuple(reversed(activated)), landing_behavior(catalog))


# -- the files ---------------------------------------------------------------------------


def _value(value: Any) -> str:
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    return repr(value)


def call(command: Command) -> str:
    """The mission API call, as a person would write it."""
    function = {EXECUTE: "execute_behavior", ACTIVATE: "activate_behavior"}.get(
        command.action, "inhibit_behavior"
    )
    parts = [repr(command.behavior)]
    odd: list[str] = []
    used: set[str] = set()
    for name, value in command.arguments:
        keyword_name = name.lower()
        if (
            keyword_name.isidentifier()
            and not keyword.iskeyword(keyword_name)
            and keyword_name not in used
        ):
            used.add(keyword_name)
            parts.append(f"{keyword_name}={_value(value)}")
        else:
            odd.append(f"{name!r}: {_value(value)}")
    if odd:
        parts.append("**{" + ", ".join(odd) + "}")
    return f"api.{function}({', '.join(parts)})"


def mission_text(mission: Sequence[Step], ending: Ending, header: Sequence[str] = ()) -> str:
    """The mission script: `header` as comments, the steps' calls in order (faults as
    comments where they strike: the world file injects them), then the ending."""
    lines = [f"# {line}".rstrip() for line in header]
    lines += ["import executive_engine_api as api", "", "", "def runMission():"]
    body = [f"    {call(c)}" for c in commands(mission)]
    struck = faults(mission)
    if struck:
        body += [
            "    # world faults (world.yaml): "
            + ", ".join(f"{f.kind} at {f.at_s:g} s" for f in struck)
        ]
    ending_calls = ending.commands()
    if ending_calls:
        body.append("    # the ending every mission has: inhibit what it activated, then land")
        body += [f"    {call(c)}" for c in ending_calls]
    if not commands(mission) and not ending_calls:
        body.append("    pass")
    return "\n".join(lines + body) + "\n"


def world_text(base: str, mission: Sequence[Step]) -> str:
    """`base` (a world file with `failures: []`) with the mission's faults."""
    struck = faults(mission)
    if not struck:
        return base
    listed = "failures:\n" + "".join(f"  - {{kind: {f.kind}, at: {f.at_s:g}}}\n" for f in struck)
    if NO_FAILURES in base:
        head, _, tail = base.rpartition(NO_FAILURES)
        return head + listed.rstrip("\n") + tail
    raise ValueError("the base world must end its failures as 'failures: []'")
