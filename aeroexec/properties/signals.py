"""The signals properties speak about, and how they are sampled from a session.

One extraction serves a recording (offline, `signals_from_recording`) and a running
session (online, the monitor feeds the bus's records): both call `SignalBuilder.topic` and
`SignalBuilder.call` with the same (name, time, data), so both produce the same samples,
and the same evaluation gives the same verdicts.

Samples sit on the executive's tick grid (`PERIOD_NS`, 10 Hz): sample k holds the state
after every message logged in [k, k+1) ticks (zero-order hold between changes). In
simulation every message falls on a tick; a live flight's messages are assigned to the
tick they fall in. A message stamped before an earlier one of the same signal (a live
vehicle's stamps can go back a little) counts from that one's tick: a tick over is what
the online monitor judged, and a late message does not change it afterwards.
"""

from __future__ import annotations

import contextlib
import math
import operator
import struct
from array import array
from bisect import bisect_right
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from aeroexec.executive.messages import TopicRecord

#: The executive's tick (aeroexec/executive/clock.py steps 0.1 s): one sample per tick.
PERIOD_NS = 100_000_000
PERIOD_S = PERIOD_NS / 1e9

#: `fault_low_battery` is raised when the battery first falls below this charge (the
#: simulator models a low battery as a level, not as a vehicle fault).
LOW_BATTERY_LEVEL = 0.2

#: Vehicle faults after which the vehicle cannot fly on: an empty battery forces a
#: landing, a seized motor stops every motion (aeroexec/vehicles/sim.py).
GROUNDING_FAULTS = ("battery_empty", "stuck_motor")


@dataclass(frozen=True, slots=True)
class SignalDoc:
    name: str
    unit: str
    meaning: str
    source: str


#: The fixed-name signals (docs/properties.md renders this table; a test keeps it true).
SIGNALS: tuple[SignalDoc, ...] = (
    SignalDoc("altitude", "m", "height of the vehicle, up", "vehicle/state position z"),
    SignalDoc("speed", "m/s", "magnitude of the velocity", "vehicle/state velocity"),
    SignalDoc("battery", "0-1", "remaining charge", "vehicle/state battery"),
    SignalDoc(
        "distance_home",
        "m",
        "horizontal distance from the first recorded position",
        "vehicle/state position",
    ),
    SignalDoc("flying", "0/1", "the vehicle is airborne", "vehicle/state flying"),
    SignalDoc("armed", "0/1", "the motors are armed", "vehicle/state armed"),
    SignalDoc("landed", "0/1", "not flying (1 - flying)", "vehicle/state flying"),
    SignalDoc(
        "link",
        "0/1",
        "the vehicle's link is up (0 while the fault is link_lost)",
        "vehicle/state fault",
    ),
    SignalDoc(
        "incompatible",
        "0/1",
        "two referenced capabilities are incompatible in the recorded catalog",
        "list_of_active_capabilities + catalog",
    ),
    SignalDoc(
        "unanswered",
        "count",
        "accepted activations of non-recurrent behaviors not yet ended by their event",
        "activate_behavior, default_values, behavior_event",
    ),
    SignalDoc(
        "grounded",
        "0/1",
        "a fault that makes flight impossible was seen "
        f"({', '.join(GROUNDING_FAULTS)}), from then on",
        "vehicle/state fault",
    ),
    SignalDoc("end", "0/1", "1 at the session's last sample", "the recording's last message"),
)

#: Per-name signals: prefix -> (unit, meaning, source).
FAMILIES: dict[str, tuple[str, str, str]] = {
    "active_": ("0/1", "behavior B is active", "list_of_active_behaviors"),
    "capability_": (
        "0/1",
        "capability C is referenced (reference count > 0)",
        "list_of_active_capabilities",
    ),
    "fault_": (
        "0/1",
        "fault K was seen, from that moment on (K: stuck_motor, battery_empty, link_lost, "
        f"mode_changed, not_connected, position_lost; low_battery when the charge falls below "
        f"{LOW_BATTERY_LEVEL:g})",
        "vehicle/state fault, battery",
    ),
    "command_": (
        "0/1",
        "1 at the sample a mission command for behavior B is issued",
        "mission/command",
    ),
}

#: Which recorded channel each fixed signal needs (a recording without it lacks them).
_VEHICLE = frozenset(
    {"altitude", "speed", "battery", "distance_home", "flying", "armed", "landed", "link"}
)


#: The vehicle/state fields each vehicle signal is made from.
_FIELDS_OF: dict[str, tuple[str, ...]] = {
    "altitude": ("position",),
    "distance_home": ("position",),
    "speed": ("velocity",),
    "battery": ("battery",),
    "flying": ("flying",),
    "landed": ("flying",),
    "armed": ("armed",),
    "link": ("fault",),
    "grounded": ("fault",),
}

#: The vehicle signals made from the state rows (link and grounded are changes): each
#: is a function of a state's row alone (and of home, the first), `row_value`.
_ROW_SIGNALS = ("altitude", "speed", "battery", "flying", "landed", "armed", "distance_home")
ROW_SIGNALS = frozenset(_ROW_SIGNALS)
#: A vehicle state's row: (sample, x, y, z, vx, vy, vz, battery, flying, armed), values
#: as the message had them; kept packed as doubles when they are numbers (a null as NaN),
#: left out of the columns otherwise (`SignalBuilder._pack`).
Row = tuple[Any, ...]
ROW_LENGTH = 10
#: A row as the table keeps it (`SignalBuilder._pack`): its values as doubles.
_PACK_ROW = struct.Struct(f"{ROW_LENGTH}d").pack
#: The row signals that are a column of the row as it is (the others are computed).
ROW_COLUMNS = {"altitude": 3, "battery": 7, "flying": 8, "armed": 9}


def _vehicle_column(name: str, held: np.ndarray, first: tuple[float, ...]) -> np.ndarray:
    """`name` at each of the state rows `held` (a view of the table's: not kept)."""
    if name == "distance_home":
        # sqrt(dx*dx + dy*dy), not hypot: each step is rounded as IEEE says, so the online
        # monitor's per-tick value (`SignalBuilder.latest`) is the same float.
        dx, dy = held[:, 1] - _coordinate(first[1]), held[:, 2] - _coordinate(first[2])
        return np.sqrt(dx * dx + dy * dy)
    if name == "speed":
        vx, vy, vz = held[:, 4], held[:, 5], held[:, 6]
        return np.sqrt(vx * vx + vy * vy + vz * vz)
    if name == "landed":
        return 1.0 - held[:, 8]
    return held[:, ROW_COLUMNS[name]]


def _step_column(changes: list[tuple[int, float]], start: int, length: int) -> np.ndarray:
    """The `length` samples from `start` of a signal kept as its changes (sample, value),
    in order: each sample holds the last change at or before it, 0 before the first (a
    change stamped before one ahead of it counts from that one's sample, as the module
    says). One repeat of the values by how many samples each holds (a search of every
    sample and a gather cost three times more)."""
    counts = []
    values = [0.0]
    held_from = 0  # where the value last added holds from (0: before the first change)
    for k, value in changes:  # a few changes: Python, not a dozen numpy calls
        begins = min(max(k - start, held_from), length)
        counts.append(begins - held_from)
        values.append(value)
        held_from = begins
    counts.append(length - held_from)
    return np.repeat(values, counts)


def _coordinate(value: Any) -> float:
    """A home coordinate as a float; NaN when it is no number (a first state with a
    null position: every distance from it is unknown, not a crash)."""
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def row_value(name: str, row: Row, first: Row) -> float:
    """`_vehicle_column` at one row, on Python floats (the same values, float for float)."""
    column = ROW_COLUMNS.get(name)
    if column is not None:
        return float(row[column])
    if name == "distance_home":
        dx, dy = float(row[1]) - float(first[1]), float(row[2]) - float(first[2])
        return math.sqrt(dx * dx + dy * dy)
    if name == "speed":
        return _speed(row)
    return 1.0 - float(row[8])  # landed


def _speed(row: Row) -> float:
    return _speed_of(row[4:7])


def _speed_of(velocity: Any) -> float:
    """sqrt(vx*vx + vy*vy + vz*vz) on floats, as `_vehicle_column` does."""
    vx, vy, vz = float(velocity[0]), float(velocity[1]), float(velocity[2])
    return math.sqrt(vx * vx + vy * vy + vz * vz)


#: A test of a vehicle signal against a number: (signal, test, bound), `Formula.threshold`.
RowTest = tuple[str, Callable[[float, float], bool], float]
#: The comparisons a row test can make, as Python writes them.
_COMPARISONS: dict[Callable[[Any, Any], bool], str] = {
    operator.lt: "<",
    operator.le: "<=",
    operator.gt: ">",
    operator.ge: ">=",
    operator.eq: "==",
    operator.ne: "!=",
}
#: How each row signal but the distance and the speed is read from a vehicle state.
_READ = {
    "battery": 'state["battery"]',
    "flying": 'state["flying"]',
    "altitude": 'state["position"][2]',
    "armed": 'state.get("armed", False)',
    "landed": '1.0 - state["flying"]',
}


def state_holds(tests: Iterable[RowTest], first: Row) -> Callable[[Mapping[str, Any]], bool]:
    """Whether a vehicle state keeps every test, `test(row_value(signal, row, first),
    bound)` for the row `SignalBuilder.vehicle_state` makes of it, computed from the
    state itself (the same floats), and is no import's guess ("defaulted"): for a
    monitor that judges each state as it comes, before it is fed. Raises what
    `row_value` raises on a state that is not numbers, or is malformed, and a TypeError
    on a value that is no number (text, even text of a number: the builder drops such a
    row). A test of the distance from a home that is no number never holds.

    One function for all the tests, written for them: inside a session, work done once
    a state costs several times what it costs alone (a loop over the tests as data, or
    a closure per test, cost 6-8 ms more of a 10-minute patrol than this, measured).
    Its source is made of the fixed lines below, one per test: the signal picks the
    line, the test its operator, and the numbers are values it is given, never text
    (nothing from a property file is in the source)."""
    namespace: dict[str, Any] = {"sqrt": math.sqrt}
    lines = []
    for i, (name, test, bound) in enumerate(tests):
        compare = _COMPARISONS[test]
        namespace[f"bound{i}"] = bound
        if name == "distance_home":
            try:
                namespace[f"home{i}"] = (float(first[1]), float(first[2]))
            except (TypeError, ValueError):
                lines.append("return False")
                continue
            # A geofence (<= or < a bound) holds on a square inside its circle without
            # the distance: |dx|, |dy| <= 0.7 bound give a distance of at most 0.99
            # bound, with any rounding (dx and dy are the floats the distance is
            # computed from), and no square of a side over 1e150 overflows.
            fence = (test is operator.le or test is operator.lt) and bound > 0
            namespace[f"side{i}"] = min(0.7 * bound, 1e150) if fence else -1.0
            lines += [
                'position = state["position"]',
                f"dx, dy = position[0] - home{i}[0], position[1] - home{i}[1]",
                f"if not (-side{i} <= dx <= side{i} and -side{i} <= dy <= side{i}):",
                f"    if not (sqrt(dx * dx + dy * dy) {compare} bound{i}):",
                "        return False",
            ]
        elif name == "speed":
            # + 0.0: a number as its float (`_speed_of`); text refused, as the builder
            # refuses it.
            lines += [
                'velocity = state["velocity"]',
                "x, y, z = velocity[0] + 0.0, velocity[1] + 0.0, velocity[2] + 0.0",
                f"if not (sqrt(x * x + y * y + z * z) {compare} bound{i}):",
                "    return False",
            ]
        else:
            lines += [f"if not ({_READ[name]} {compare} bound{i}):", "    return False"]
    lines.append('return "defaulted" not in state')
    source = "def holds(state):\n" + "".join(f"    {line}\n" for line in lines)
    exec(compile(source, "<state tests>", "exec"), namespace)
    holds: Callable[[Mapping[str, Any]], bool] = namespace["holds"]
    return holds


def _row_of(k: int, data: dict[str, Any]) -> Row:
    """The row of a state whose position or velocity is not 3 long: their first three
    (IndexError when shorter), as a position of 3 gives them."""
    position, velocity = data["position"], data["velocity"]
    return (
        k,
        position[0],
        position[1],
        position[2],
        velocity[0],
        velocity[1],
        velocity[2],
        data["battery"],
        data["flying"],
        data.get("armed", False),
    )


def is_known_signal(name: str) -> bool:
    return any(name == s.name for s in SIGNALS) or any(
        name.startswith(prefix) and len(name) > len(prefix) for prefix in FAMILIES
    )


@dataclass(frozen=True)
class Signals:
    """Sampled signals: `values[name][k]` at time `k * PERIOD_S`; `missing[name]` says why
    a signal the session could not give is absent."""

    length: int
    values: Mapping[str, np.ndarray]
    #: Channels the session had (decides which per-name signals exist, as zeros).
    sources: frozenset[str]
    #: vehicle/state fields the recording had only as an importer's defaults.
    defaulted: frozenset[str] = frozenset()

    def times(self) -> list[float]:
        return [k * PERIOD_S for k in range(self.length)]

    def get(self, name: str) -> np.ndarray | None:
        """The samples of `name`, or None when the session could not give it."""
        found = self.values.get(name)
        if found is not None:
            return found
        if name.startswith("fault_") and "fault" in self.defaulted:
            return None
        for prefix, needs in _FAMILY_SOURCES.items():
            if name.startswith(prefix) and needs in self.sources:
                return np.zeros(self.length)  # never active, never seen, never issued
        return None

    def why_missing(self, name: str) -> str:
        fields = _FIELDS_OF.get(name, ("fault",) if name.startswith("fault_") else ())
        guessed = [f for f in fields if f in self.defaulted]
        if guessed:
            return f"the recording's vehicle states lack {guessed[0]} (an import's default)"
        need = _SOURCE_OF.get(name)
        if need is None:
            for prefix, source in _FAMILY_SOURCES.items():
                if name.startswith(prefix):
                    need = source
        if name == "incompatible" and "list_of_active_capabilities" in self.sources:
            return "the recording carries no catalog (catalog.yaml attachment)"
        if need == "vehicle/state" and need in self.sources:
            return "none of the recording's vehicle states is a row of numbers"
        return f"the recording has no {need} messages" if need else "unknown signal"


_FAMILY_SOURCES = {
    "active_": "list_of_active_behaviors",
    "capability_": "list_of_active_capabilities",
    "fault_": "vehicle/state",
    "command_": "mission/command",
}
_SOURCE_OF = {name: "vehicle/state" for name in _VEHICLE} | {
    "incompatible": "list_of_active_capabilities",
    "unanswered": "activate_behavior",
    "grounded": "vehicle/state",
    "end": "any",
}


class SignalBuilder:
    """Turns a session's messages, in order, into `Signals`.

    `conflicts(capability)`: the capabilities incompatible with it (from the catalog);
    None when the session has no catalog (then `incompatible` is missing)."""

    def __init__(self, conflicts: Callable[[str], Iterable[str]] | None = None) -> None:
        self._conflicts = conflicts
        #: name -> list of (sample, value) changes; the value holds until the next one.
        self._changes: dict[str, list[tuple[int, float]]] = {}
        self._current: dict[str, float] = {}
        self._pulses: dict[str, list[int]] = {}
        self._sources: set[str] = set()
        self._last = -1
        #: Whether each signal's changes and pulses, and the state rows up to
        #: `_rows_checked`, are in the order of their samples (a live vehicle's stamps
        #: can go back a little): then a window's start is found by a search.
        self._changes_in_order = True
        self._rows_in_order = True
        self._rows_checked = 0
        self._active: frozenset[str] = frozenset()
        self._capabilities: frozenset[str] = frozenset()
        self._recurrent: dict[str, bool] = {}
        self._pending: dict[int, str] = {}
        self._answered: set[int] = set()
        #: The vehicle states' rows that are numbers (`vehicle_state`), packed: ROW_LENGTH
        #: doubles each. Packed, not kept as tuples: a tuple would keep the state's float
        #: objects alive, a few MB of an hour's session that the allocator then cannot
        #: reuse (measured: most of what monitoring cost in a session beyond its own
        #: work), and the columns are a copy away instead of a conversion.
        self._table = array("d")
        self._add_row = self._table.frombytes
        #: The first state's row (home); the last one's when it was odd (`_odd_state`),
        #: else it is the table's last; whether they are numbers (in the table).
        self._first_row: Row | None = None
        self._last_row: Row | None = None
        self._first_numeric = False
        self._last_numeric = False
        self._last_fault: Any = None
        #: vehicle/state fields some state had only as an importer's default.
        self._defaulted: set[str] = set()
        self._faults: set[str] = set()

    # -- input ------------------------------------------------------------------------------
    def use_catalog(self, conflicts: Callable[[str], Iterable[str]]) -> None:
        """The catalog's capability conflicts, when they become known (a recording's
        attachment, before its messages; a session's catalog, after the executive's first
        messages: the capabilities held so far are judged at once)."""
        self._conflicts = conflicts
        if "list_of_active_capabilities" in self._sources:
            self._set(max(self._last, 0), "incompatible", float(self._any_conflict()))

    def mark_time(self, t_ns: int) -> None:
        """A message no signal reads: it still extends the session."""
        k = t_ns // PERIOD_NS
        if k > self._last:
            self._last = k

    def topic(self, name: str, t_ns: int, data: Any) -> None:
        if name == "vehicle/state":
            self.vehicle_state(t_ns, data)
            return
        k = t_ns // PERIOD_NS
        if k > self._last:
            self._last = k
        if not isinstance(data, dict):
            return
        if name == "list_of_active_behaviors":
            self._sources.add(name)
            self._set_members(k, "active_", self._active, data.get("behaviors"), "_active")
        elif name == "list_of_active_capabilities":
            self._sources.add(name)
            names = [
                c.get("name")
                for c in data.get("capabilities") or ()
                if isinstance(c, dict) and (c.get("references") or 0) > 0
            ]
            self._set_members(k, "capability_", self._capabilities, names, "_capabilities")
            if self._conflicts is not None:
                self._set(k, "incompatible", float(self._any_conflict()))
        elif name == "mission/command":
            self._sources.add(name)
            behavior = data.get("behavior")
            if isinstance(behavior, str) and behavior:
                pulses = self._pulses.setdefault("command_" + behavior, [])
                if not pulses or pulses[-1] != k:
                    if pulses and k < pulses[-1]:
                        self._changes_in_order = False
                    pulses.append(k)
        elif name == "behavior_event":
            uid = data.get("uid")
            if isinstance(uid, int):
                # An event can come before its activation's call record: a call is
                # recorded when it completes, and a start that fails at once answers
                # inside it.
                self._answered.add(uid)
                if self._pending.pop(uid, None) is not None:
                    self._set(k, "unanswered", float(len(self._pending)))

    def call(self, service: str, t_ns: int, request: Any, response: Any) -> None:
        k = t_ns // PERIOD_NS
        if k > self._last:
            self._last = k
        if not isinstance(response, dict) or not isinstance(request, dict):
            return
        if service == "default_values":
            behavior = request.get("behavior")
            if isinstance(behavior, str):
                self._recurrent[behavior] = bool(response.get("recurrent"))
        elif service == "activate_behavior":
            self._sources.add(service)
            behavior = request.get("behavior")
            uid = response.get("uid")
            if (
                response.get("ok")
                and isinstance(uid, int)
                and isinstance(behavior, str)
                and not self._recurrent.get(behavior, False)
                and uid not in self._answered
            ):
                self._pending[uid] = behavior
            self._set(k, "unanswered", float(len(self._pending)))

    # -- output -----------------------------------------------------------------------------
    @property
    def last_sample(self) -> int:
        """The last sample so far (-1 before any message)."""
        return self._last

    @property
    def home_row(self) -> Row | None:
        """The first vehicle state's row (home, for `distance_home`), None before one."""
        return self._first_row

    def finish(self, start: int = 0, *, final: bool = True) -> Signals:
        """The samples from `start` to the last one. `final`: the session has ended (the
        `end` signal is 1 on its last sample; a window of a running session has no end)."""
        length = self._last + 1 - start if self._last >= start else 0
        values: dict[str, np.ndarray] = {}
        for name, changes in self._changes.items():
            # A count or a 0/1 flag is 0 until its first change.
            values[name] = _step_column(changes, start, length)
        first_row = self._first_row
        if self._table and length and first_row is not None:
            names = [name for name in _ROW_SIGNALS if not self._guessed(name)]
            values.update(self._row_columns(start, length, names))
            first_k = int(first_row[0])
            for name in ("link", "grounded"):
                if name in values and first_k >= start:
                    # Known from the first state: its value holds before it too.
                    values[name][: first_k - start] = values[name][first_k - start]
        for name, pulses in self._pulses.items():
            column = np.zeros(length)
            inside = [k - start for k in pulses if k >= start]
            column[inside] = 1.0
            values[name] = column
        if length:
            end = np.zeros(length)
            if final:
                end[-1] = 1.0
            values["end"] = end
        for name in list(values):
            if self._guessed(name):
                del values[name]
        return Signals(length, values, frozenset(self._sources), frozenset(self._defaulted))

    def _guessed(self, name: str) -> bool:
        """Whether `name` comes from a field the recording only had as a default."""
        fields = _FIELDS_OF.get(name, ("fault",) if name.startswith("fault_") else ())
        return any(f in self._defaulted for f in fields)

    def latest(self, names: Iterable[str], k: int) -> dict[str, float] | None:
        """The values of `names` at sample `k`, the last one so far (no message after it
        yet), as `window` gives them there, float for float, without arrays: what an
        online monitor judges each tick by. None when one of them is missing, or not
        known yet at that sample without what later messages say (a vehicle signal
        before the first state, a state that is no row of numbers)."""
        values: dict[str, float] = {}
        row: Row | None = None
        home = self._first_row
        if self._defaulted and any(self._guessed(name) for name in names):
            return None
        current = self._current
        for name in names:
            if name in ROW_SIGNALS:
                if row is None:
                    row = self._numeric_last_row()
                    if row is None or home is None:
                        return None
                values[name] = row_value(name, row, home)
            elif name in current:
                values[name] = current[name]
            elif name in self._pulses:
                values[name] = 1.0 if self._pulses[name][-1] == k else 0.0
            elif name == "end" or any(
                name.startswith(prefix) and source in self._sources
                for prefix, source in _FAMILY_SOURCES.items()
            ):
                values[name] = 0.0
            else:
                return None
        return values

    @property
    def last_row(self) -> Row | None:
        """The last vehicle state's row (a state of numbers: as the table holds it,
        floats), None before one."""
        if self._last_row is None and self._table:
            return tuple(self._table[-ROW_LENGTH:])
        return self._last_row

    def _numeric_last_row(self) -> Row | None:
        """The last state row, when it and the first (home) are rows of numbers (a row
        that is not is dropped offline: its tick holds an earlier one); else None."""
        if not (self._last_numeric and self._first_numeric):
            return None
        return self.last_row

    def window(
        self, start: int, names: Iterable[str], end: int | None = None
    ) -> dict[str, np.ndarray] | None:
        """The samples from `start` to `end` (default: the last one so far) of the
        signals `names`, as `finish(start, final=False)` gives them, built from only what
        that window needs (an online check looks at a few ticks); None when one of them
        is missing."""
        length = (self._last if end is None else end) + 1 - start
        if length <= 0:
            return None
        out: dict[str, np.ndarray] = {}
        row_names: list[str] = []
        for name in names:
            changes = self._changes.get(name)
            if self._guessed(name):
                return None
            if name in _ROW_SIGNALS:
                if not self._table or self._first_row is None:
                    return None
                row_names.append(name)
            elif changes is not None:
                if self._changes_in_order:  # else all: `_step_column` orders them
                    changes = changes[max(bisect_right(changes, (start, math.inf)) - 1, 0) :]
                out[name] = _step_column(changes, start, length)
                first_k = int(self._first_row[0]) if self._first_row is not None else -1
                if name in ("link", "grounded") and start <= first_k < self._last + 1:
                    # Known from the first state: its value holds before it too.
                    out[name][: first_k - start] = out[name][first_k - start]
            elif name in self._pulses:
                pulses = self._pulses[name]
                if self._changes_in_order:
                    pulses = pulses[bisect_right(pulses, start - 1) :]
                column = np.zeros(length)
                column[[k - start for k in pulses if start <= k < start + length]] = 1.0
                out[name] = column
            elif name == "end" or any(
                name.startswith(prefix) and source in self._sources
                for prefix, source in _FAMILY_SOURCES.items()
            ):
                out[name] = np.zeros(length)
            else:
                return None
        if row_names:
            out.update(self._row_columns(start, length, row_names))
        return out

    # -- internals --------------------------------------------------------------------------
    def _set(self, k: int, name: str, value: float) -> None:
        if self._current.get(name) == value:
            return
        self._current[name] = value
        changes = self._changes.setdefault(name, [])
        if changes and changes[-1][0] == k:
            changes[-1] = (k, value)  # the state at the end of the tick counts
        else:
            if changes and k < changes[-1][0]:
                self._changes_in_order = False
            changes.append((k, value))

    def _set_members(
        self, k: int, prefix: str, before: frozenset[str], names: Any, attr: str
    ) -> None:
        now = frozenset(n for n in names or () if isinstance(n, str))
        for name in before - now:
            self._set(k, prefix + name, 0.0)
        for name in now - before:
            self._set(k, prefix + name, 1.0)
        setattr(self, attr, now)

    def _any_conflict(self) -> bool:
        assert self._conflicts is not None
        held = self._capabilities
        return any(other in held for name in held for other in self._conflicts(name))

    def vehicle_states(self, records: Iterable[TopicRecord]) -> None:
        """`vehicle_state` of each record in turn (a monitor feeds its states in
        batches), with what it looks up once a batch instead of once a state (0.45 of
        2.4 ms on a 10-minute patrol's states): the common state (a row of numbers, no
        fault or low battery first seen, none of an import's defaults, after the first
        sample) goes straight into the table; any other takes `vehicle_state` itself."""
        add_row, last, last_fault = self._add_row, self._last, self._last_fault
        usual_battery = -math.inf if "low_battery" in self._faults else LOW_BATTERY_LEVEL
        added = False
        for record in records:
            data = record.data
            k = record.log_time_ns // PERIOD_NS
            try:
                x, y, z = data["position"]
                vx, vy, vz = data["velocity"]
                battery = data["battery"]
                row = _PACK_ROW(
                    k, x, y, z, vx, vy, vz, battery, data["flying"], data.get("armed", False)
                )
                # The fault is None before the first sample: the first takes the long way.
                usual = (
                    battery >= usual_battery
                    and (data.get("fault") or "") == last_fault
                    and "defaulted" not in data
                )
            except (struct.error, ValueError, LookupError, TypeError, AttributeError):
                usual = False
            if usual:
                add_row(row)
                if k > last:
                    last = k
                added = True
                continue
            if added:  # what `vehicle_state` says of the rows added so far
                self._last_row, self._last_numeric, added = None, True, False
            self._last = last
            self.vehicle_state(record.log_time_ns, data)
            last, last_fault = self._last, self._last_fault
            usual_battery = -math.inf if "low_battery" in self._faults else LOW_BATTERY_LEVEL
        self._last = last
        if added:
            self._last_row, self._last_numeric = None, True

    def vehicle_state(self, t_ns: int, data: Any) -> bool:
        """A `vehicle/state` message (what `topic` does with one), in one call: the hot
        path online, a state per tick. Returns whether the state is a sample (False: it
        is malformed). The columns are made, and the values checked, at the end; faults,
        rare, are changes."""
        k = t_ns // PERIOD_NS
        if k > self._last:
            self._last = k
        try:
            # A state of numbers, each field as long as it should be, straight into the
            # table: no row of Python objects is kept (the others take `_odd_state`).
            x, y, z = data["position"]
            vx, vy, vz = data["velocity"]
            battery = data["battery"]
            self._add_row(
                _PACK_ROW(k, x, y, z, vx, vy, vz, battery, data["flying"], data.get("armed", False))
            )
            self._last_row = None
            self._last_numeric = True
            low = battery < LOW_BATTERY_LEVEL
            fault = data.get("fault") or ""
        except (struct.error, ValueError, LookupError, TypeError, AttributeError):
            odd = self._odd_state(k, data)
            if odd is None:
                return False
            low, fault = odd
        if self._first_row is None:
            self._sources.add("vehicle/state")
            self._first_row = self._last_row or tuple(self._table[-ROW_LENGTH:])
            self._first_numeric = self._last_numeric
        if "defaulted" in data:  # a bag's import filled these in: not the vehicle's word
            defaulted = data["defaulted"]
            if defaulted:
                self._defaulted.update(d for d in defaulted if isinstance(d, str))
        if low and "low_battery" not in self._faults:
            self._fault(k, "low_battery")
        if fault != self._last_fault:
            self._last_fault = fault
            kind = fault.split(":", 1)[0] if isinstance(fault, str) else ""
            self._set(k, "link", 0.0 if kind == "link_lost" else 1.0)
            if kind:
                self._fault(k, kind)
            self._set(k, "grounded", float(bool(self._faults & set(GROUNDING_FAULTS))))
        return True

    def _odd_state(self, k: int, data: Any) -> tuple[bool, Any] | None:
        """A state the table did not take as it came: a position or velocity longer than
        3 (their first three count), values that are not numbers, or no state at all.
        Returns (low battery, fault) for a sample, None for a malformed state (no
        sample; the channel is still there, unless it is no mapping at all)."""
        try:
            row = _row_of(k, data)
            # A velocity that is no numbers makes no sample (its square is the speed).
            0.0 + row[4] + row[5] + row[6]
            low = row[7] < LOW_BATTERY_LEVEL
            fault = data.get("fault") or ""
        except (KeyError, IndexError, TypeError, AttributeError):
            if isinstance(data, dict):
                self._sources.add("vehicle/state")
            return None
        self._last_row = row
        self._last_numeric = self._pack(row)
        return low, fault

    def _pack(self, row: Row) -> bool:
        """Add `row` to the table; True when its values are all numbers. A null is kept
        as NaN (a position of nulls is unknown, not absent); a row with a value that is
        no number otherwise (text, an integer beyond a float) is left out, as a whole."""
        try:
            self._add_row(_PACK_ROW(*row))
            return True
        except struct.error:
            pass
        with contextlib.suppress(struct.error):
            self._add_row(_PACK_ROW(*[math.nan if value is None else value for value in row]))
        return False

    def _row_columns(self, start: int, length: int, names: Iterable[str]) -> dict[str, np.ndarray]:
        """The row signals `names` at the `length` samples from `start`: each sample
        holds the last numeric state row at or before it (the last state of a tick
        counts; before the first, the first: a vehicle signal is known from the
        session's start). Each signal is computed on the rows, then repeated by how many
        samples each row holds: new arrays, so the table can grow on, and no copy of the
        whole rows (half a megabyte a 10-minute session, whose fresh pages cost more
        than the rest of the end of it, measured)."""
        first_row = self._first_row
        assert first_row is not None
        packed = np.frombuffer(self._table, dtype=float).reshape(-1, ROW_LENGTH)
        if self._rows_in_order and len(packed) > self._rows_checked:
            since = packed[max(self._rows_checked - 1, 0) :, 0]
            self._rows_in_order = not (since[1:] < since[:-1]).any()
            self._rows_checked = len(packed)
            del since
        # A row stamped before one ahead of it holds from that one's sample (`_step_column`).
        at = packed[:, 0] if self._rows_in_order else np.maximum.accumulate(packed[:, 0])
        first = max(int(np.searchsorted(at, start, side="right")) - 1, 0)
        # Each row holds from its sample (the first: from `start`) to the next row's.
        bounds = np.clip(at[first + 1 :].astype(np.intp) - start, 0, length)
        counts = np.diff(bounds, prepend=0, append=length)
        rows = packed[first:]
        columns = {
            name: np.repeat(_vehicle_column(name, rows, first_row), counts) for name in names
        }
        del packed, at, rows  # the table is exported while a view of it lives: no growth
        return columns

    def _fault(self, k: int, kind: str) -> None:
        if kind not in self._faults:
            self._faults.add(kind)
            self._set(k, "fault_" + kind, 1.0)
