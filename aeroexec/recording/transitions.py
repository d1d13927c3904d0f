"""The transitions of a recording, and the moments `FAULT@WHEN` names.

A transition is what the executive did at one instant: a behavior activated (an accepted
`activate_behavior`), a behavior ended (its `behavior_event`), a capability referenced or
released (`list_of_active_capabilities`). Each is named `KIND:NAME#N` (the N-th of its
kind and name, from 1): `activate:GO_TO_POINT#2`, `end:TAKE_OFF#1`,
`capability:+SELF_LOCALIZATION_BY_ODOMETRY#1`. They are read from the recording through
the recording reader, in file order, so replay (`--inject`) and explore name the same
moments.

WHEN (`replay --inject FAULT@WHEN`): a time of the session (`12.5s`), or a transition with
an optional `#N` (default 1) and offset (`activate:LAND+0.5s`, `end:TAKE_OFF-1s`).
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Callable
from dataclasses import dataclass

from aeroexec.errors import InjectionError, Mark
from aeroexec.recording.reader import open_recording
from aeroexec.recording.schemas import MESSAGE_ENCODING, SERVICE_CALL

NS_PER_S = 1_000_000_000
KINDS = ("activate", "end", "capability")
#: Log times from this on are instants of the wall clock (a live flight's, a bag's): the
#: session's time is counted from its first message.
ABSOLUTE_NS = 10**18

_TIME = re.compile(r"(\d+(?:\.\d*)?|\.\d+)s")
_TRANSITION = re.compile(
    r"(?P<kind>[a-z]+):(?P<name>[+-]?[A-Za-z0-9_./-]*?)(?:#(?P<n>\d+))?"
    r"(?:(?P<offset>[+-](?:\d+(?:\.\d*)?|\.\d+))s)?"
)
SYNTAX = (
    "a time (12.5s) or a transition KIND:NAME[#N][+/-SECONDSs] with KIND activate, end or "
    "capability (activate:GO_TO_POINT#2, end:TAKE_OFF, capability:+SELF_LOCALIZATION_BY_"
    "ODOMETRY, activate:LAND+0.5s)"
)


@dataclass(frozen=True, slots=True)
class RecordedTransition:
    kind: str  # activate | end | capability
    #: The behavior, or the capability with its sign (`+NAME` referenced, `-NAME` released).
    name: str
    #: Which one of its kind and name, from 1.
    occurrence: int
    #: Session time (from the first message).
    time_ns: int
    #: For an end: its event code.
    detail: str = ""

    @property
    def label(self) -> str:
        return f"{self.kind}:{self.name}#{self.occurrence}"

    @property
    def behavior(self) -> str:
        """The behavior or capability it concerns (no sign)."""
        return self.name.lstrip("+-")


@dataclass(frozen=True, slots=True)
class Moment:
    """What a WHEN resolved to: when a fault strikes (the first simulator step that
    reaches `due_ns`), and the transition it was named after (None for a time)."""

    due_ns: int
    transition: RecordedTransition | None = None
    offset_ns: int = 0


@dataclass(frozen=True, slots=True)
class Timeline:
    """A recording's transitions, its length (session time of its last message) and the
    vehicle state it started from (None: it has none)."""

    transitions: tuple[RecordedTransition, ...]
    end_ns: int
    first_state: dict[str, object] | None = None


def read_transitions(path: str | os.PathLike[str]) -> tuple[RecordedTransition, ...]:
    """Every transition of the recording, in the order they happened."""
    return read_timeline(path).transitions


def read_timeline(
    path: str | os.PathLike[str], enough: Callable[[list[RecordedTransition]], bool] | None = None
) -> Timeline:
    """One pass over the recording: its transitions, length and first vehicle state.
    `enough(transitions so far)`: stop reading as soon as it says so (then the length is
    where reading stopped)."""
    found: list[RecordedTransition] = []
    first_state: dict[str, object] | None = None
    last = 0
    counts: dict[tuple[str, str], int] = {}
    held: tuple[str, ...] = ()
    origin: int | None = None

    def add(kind: str, name: str, t_ns: int, detail: str = "") -> None:
        n = counts[(kind, name)] = counts.get((kind, name), 0) + 1
        found.append(RecordedTransition(kind, name, n, t_ns, detail))

    for message in open_recording(path).messages():
        if enough is not None and enough(found):
            break
        if origin is None:
            origin = message.log_time_ns if message.log_time_ns >= ABSOLUTE_NS else 0
        t_ns = message.log_time_ns - origin
        last = max(last, t_ns)
        channel = message.channel
        name = _inside(channel.topic)
        # Only the few channels transitions come from are decoded (a long recording is
        # mostly vehicle states, of which only the first is wanted).
        is_call = channel.schema_name == SERVICE_CALL
        if is_call and name != "activate_behavior":
            continue
        if not is_call and name not in _TOPICS:
            continue
        if name == "vehicle/state" and first_state is not None:
            continue
        if channel.message_encoding != MESSAGE_ENCODING:
            continue
        try:
            data = json.loads(message.data)
        except ValueError:
            continue
        if not isinstance(data, dict):
            continue
        if is_call:
            request, response = data.get("request"), data.get("response")
            if (
                isinstance(request, dict)
                and isinstance(response, dict)
                and data.get("parent_seq") is None
                and response.get("ok")
                and isinstance(request.get("behavior"), str)
            ):
                add("activate", request["behavior"], t_ns)
        elif name == "vehicle/state":
            first_state = data
        elif name == "behavior_event":
            behavior = data.get("name")
            if isinstance(behavior, str) and behavior:
                add("end", behavior, t_ns, str(data.get("code", "")))
        else:  # list_of_active_capabilities
            now = _referenced(data)
            for cap in held:
                if cap not in now:
                    add("capability", "-" + cap, t_ns)
            for cap in now:
                if cap not in held:
                    add("capability", "+" + cap, t_ns)
            held = now
    return Timeline(tuple(found), last, first_state)


_TOPICS = frozenset({"behavior_event", "list_of_active_capabilities", "vehicle/state"})


def _inside(topic: str) -> str:
    """The topic inside the drone's namespace (`/drone1/behavior_event` -> `behavior_event`)."""
    parts = topic.split("/", 2)
    return parts[2] if len(parts) == 3 and parts[0] == "" else topic.lstrip("/")


def _referenced(data: dict[str, object]) -> tuple[str, ...]:
    items = data.get("capabilities")
    if not isinstance(items, list):
        return ()
    return tuple(
        str(c.get("name"))
        for c in items
        if isinstance(c, dict) and isinstance(c.get("name"), str) and (c.get("references") or 0) > 0
    )


def is_time(when: str) -> bool:
    """Whether WHEN is a time (`12.5s`), which needs no transition."""
    return _TIME.fullmatch(when.strip()) is not None


def named(when: str) -> tuple[str, str, int] | None:
    """The transition (kind, name, occurrence) a WHEN names, None for a time or a WHEN
    that does not parse (`resolve_when` says why)."""
    match = _TRANSITION.fullmatch(when.strip())
    if match is None or _TIME.fullmatch(when.strip()) or match["kind"] not in KINDS:
        return None
    return (match["kind"], match["name"], int(match["n"]) if match["n"] else 1)


def _seconds_ns(text: str) -> int:
    return round(float(text) * NS_PER_S)


def resolve_when(
    when: str, transitions: tuple[RecordedTransition, ...], end_ns: int, recording: str
) -> Moment:
    """The moment `when` names in a recording with these transitions and this length.

    A time strikes at the first step that reaches it. A transition happened inside a
    tick, after the vehicle had moved: a fault named after it (plus its offset) strikes
    at the first step after that moment. `InjectionError` naming what exists for anything else."""
    text = when.strip()

    def fail(message: str) -> InjectionError:
        return InjectionError(f"WHEN {text!r}: {message}", Mark(recording))

    timed = _TIME.fullmatch(text)
    if timed:
        due = _seconds_ns(timed[1])
        if due > end_ns:
            raise fail(f"past the end of the recording (it ends at {end_ns / NS_PER_S:g} s)")
        return Moment(due)
    match = _TRANSITION.fullmatch(text)
    if match is None or match["kind"] not in KINDS or not match["name"]:
        raise InjectionError(f"WHEN {text!r}: expected {SYNTAX}")
    kind, name = match["kind"], match["name"]
    if kind == "capability" and name[0] not in "+-":
        raise InjectionError(
            f"WHEN {text!r}: say whether the capability is referenced (+{name}) or released "
            f"(-{name})"
        )
    occurrence = int(match["n"]) if match["n"] else 1
    offset = _seconds_ns(match["offset"]) if match["offset"] else 0
    same = [t for t in transitions if t.kind == kind and t.name == name]
    if not same:
        raise fail(f"the recording has no {kind}:{name} ({_what_exists(kind, transitions)})")
    if occurrence < 1 or occurrence > len(same):
        times = "once" if len(same) == 1 else f"{len(same)} times"
        raise fail(
            f"{kind}:{name} happens {times} in the recording: #{occurrence} does not exist "
            f"(#1..#{len(same)})"
        )
    transition = same[occurrence - 1]
    # Strictly after the moment named: 1 ns later is the next step.
    due = transition.time_ns + offset + 1
    if due < 0:
        raise fail(f"{due / NS_PER_S:g} s is before the session began")
    return Moment(due, transition, offset)


def _what_exists(kind: str, transitions: tuple[RecordedTransition, ...]) -> str:
    counts: dict[str, int] = {}
    for t in transitions:
        if t.kind == kind:
            counts[t.name] = counts.get(t.name, 0) + 1
    if not counts:
        return f"it has no {kind} transition at all"
    listed = ", ".join(f"{n} ×{c}" if c > 1 else n for n, c in counts.items())
    return f"it has {listed}"
