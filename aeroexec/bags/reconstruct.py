"""Rebuild the behavior commands of a bag from its active-behavior lists and events.

A 2017 Aerostack mission asked the coordinator through services (`activate_behavior`,
`inhibit_behavior`), and a bag holds topics only. What the bag does show is the
coordinator's `list_of_active_behaviors` and the behaviors' `behavior_event`s; from
their changes the commands are reconstructed (every output it invents carries
`"reconstructed": true`):

* a behavior **appearing** in the list was activated then: a `mission/command`
  `activate_behavior` (arguments from the list's `behavior_commands` when the message
  has them, 2018+) and an accepted `activate_behavior` call with a fresh uid, listing the
  behaviors it preempted;
* a behavior **disappearing** from the list with an end event other than INTERRUPTED
  ended by itself: no command;
* disappearing with INTERRUPTED while another behavior appeared within the grace time:
  **preempted** by it (the event's detail becomes `preempted by X`, as aeroexec says);
* disappearing **without an end event** (or INTERRUPTED with no activation around it):
  **inhibited**: a `mission/command` `inhibit_behavior` and an accepted call, plus, when
  the bag has no event, an INTERRUPTED `inhibited` event (what aeroexec would publish);
* an end event of a behavior that never showed in the list (it ended before the list
  caught up, or the bag has no list) was activated just before: reconstructed there.

Commands a bag does carry (mapped command topics) are kept as they are and explain the
list change that follows them within the grace time (no reconstructed command then).

Related messages are up to `grace` apart (bag time). Each input is decided once
everything up to 2 x grace after it has been seen, so `horizon` (the oldest input not
decided yet) tells the importer which outputs may still gain a message before them.
Uids count activations from 1, like the executive's.
"""

from __future__ import annotations

import bisect
from collections import Counter
from dataclasses import dataclass, field
from typing import Any

from aeroexec.bags.extract import ActiveList, Command, Event, parse_arguments
from aeroexec.executive.messages import EventCode

COMMAND = "mission/command"
ACTIVATE = "activate_behavior"
INHIBIT = "inhibit_behavior"
EVENT = "behavior_event"
LIST = "list_of_active_behaviors"
#: Event details as aeroexec's coordinator writes them.
PREEMPTED_BY = "preempted by {}"
INHIBITED = "inhibited"
#: An end event this long after its behavior was reconstructed as inhibited is that
#: activation's real end (in grace units): counted, kept raw only, no second end event.
LATE_EVENT_GRACES = 4


@dataclass(frozen=True, slots=True)
class Output:
    """A derived message: `topic` inside the drone's namespace; `call` marks a service
    call record (the importer numbers them: `seq`)."""

    time_ns: int
    topic: str
    data: dict[str, Any]
    call: bool = False


@dataclass(slots=True)
class _ListIn:
    time_ns: int
    names: tuple[str, ...]
    appeared: tuple[str, ...]
    dropped: tuple[str, ...]
    arguments: dict[str, str]


@dataclass(slots=True)
class _EventIn:
    time_ns: int
    event: Event


@dataclass(slots=True)
class _CommandIn:
    time_ns: int
    kind: str  # ACTIVATE or INHIBIT
    command: Command
    consumed: bool = False


_Input = _ListIn | _EventIn | _CommandIn


@dataclass(slots=True)
class _Activation:
    uid: int
    name: str
    start_ns: int
    in_list: bool
    ended: bool = False
    end_ns: int | None = None
    #: Set when the drop was decided before the event came: the event's detail.
    detail: str = ""
    #: Reconstructed as inhibited (command already emitted).
    inhibited: bool = False
    #: Closed by a reconstructed (synthetic) event.
    synthetic_end: bool = False


@dataclass(slots=True)
class Stats:
    activations: int = 0
    inhibitions: int = 0
    synthetic_events: int = 0
    preemptions: int = 0
    late_events: int = 0
    events: int = 0
    unknown_codes: Counter[str] = field(default_factory=Counter)
    bad_arguments: int = 0


@dataclass(frozen=True, slots=True)
class _Drop:
    kind: str  # "ended" | "preempted" | "inhibited"
    by: str | None
    event: _EventIn | None


class Reconstructor:
    def __init__(self, grace_ns: int) -> None:
        self.grace = grace_ns
        self.stats = Stats()
        self._inputs: list[_Input] = []
        self._times: list[int] = []
        self._next = 0  # first input not decided yet
        self._last_list: tuple[str, ...] = ()  # as ingested
        self._written_list: tuple[str, ...] = ()
        self._acts: dict[str, _Activation] = {}
        self._uid = 0
        self._out: list[Output] = []
        self._drops: dict[tuple[int, str], _Drop] = {}

    # -- input (in bag time order) -------------------------------------------------------
    def active_list(self, time_ns: int, value: ActiveList) -> None:
        before = set(self._last_list)
        after = set(value.names)
        appeared = tuple(n for n in value.names if n not in before)
        dropped = tuple(n for n in self._last_list if n not in after)
        self._last_list = value.names
        self._add(_ListIn(time_ns, value.names, appeared, dropped, dict(value.arguments)))

    def event(self, time_ns: int, value: Event) -> None:
        self._add(_EventIn(time_ns, value))

    def command(self, time_ns: int, kind: str, value: Command) -> None:
        self._add(_CommandIn(time_ns, kind, value))

    # -- progress ----------------------------------------------------------------------------
    @property
    def horizon(self) -> int | None:
        """Bag time of the oldest input not decided yet (outputs at or after it may still
        be preceded by outputs of that input); None when everything is decided."""
        return self._times[self._next] if self._next < len(self._inputs) else None

    def advance(self, now_ns: int) -> None:
        """Decide every input older than `now_ns` - 2 x grace (all its context is in)."""
        limit = now_ns - 2 * self.grace
        while self._next < len(self._inputs) and self._times[self._next] < limit:
            self._decide(self._inputs[self._next])
            self._next += 1
        self._prune()

    def finish(self) -> None:
        while self._next < len(self._inputs):
            self._decide(self._inputs[self._next])
            self._next += 1

    def take(self) -> list[Output]:
        out, self._out = self._out, []
        return out

    # -- internals ---------------------------------------------------------------------------
    def _add(self, item: _Input) -> None:
        self._inputs.append(item)
        self._times.append(item.time_ns)

    def _prune(self) -> None:
        """Forget decided inputs no later decision can look back to."""
        if self._next < 256:
            return
        current = self._times[self._next - 1]
        keep_from = bisect.bisect_left(self._times, current - 4 * self.grace, 0, self._next)
        if keep_from > 128:
            del self._inputs[:keep_from]
            del self._times[:keep_from]
            self._next -= keep_from

    def _window(self, start_ns: int, end_ns: int) -> list[_Input]:
        lo = bisect.bisect_left(self._times, start_ns)
        hi = bisect.bisect_right(self._times, end_ns)
        return self._inputs[lo:hi]

    def _emit(self, time_ns: int, topic: str, data: dict[str, Any], call: bool = False) -> None:
        self._out.append(Output(time_ns, topic, data, call))

    def _decide(self, item: _Input) -> None:
        if isinstance(item, _ListIn):
            self._decide_list(item)
        elif isinstance(item, _EventIn):
            self._decide_event(item)
        else:
            self._decide_command(item)

    # -- classification (pure over the inputs, cached) -------------------------------------
    def _classify(self, name: str, drop: _ListIn) -> _Drop:
        key = (drop.time_ns, name)
        found = self._drops.get(key)
        if found is not None:
            return found
        g = self.grace
        window = self._window(drop.time_ns - g, drop.time_ns + g)
        event = next((i for i in window if isinstance(i, _EventIn) and i.event.name == name), None)
        if event is not None and event.event.code is not EventCode.INTERRUPTED:
            result = _Drop("ended", None, event)
        else:
            by = self._preemptor(name, drop, window)
            if event is not None and by is not None:
                result = _Drop("preempted", by, event)
            else:
                result = _Drop("inhibited", None, event)
        self._drops[key] = result
        return result

    @staticmethod
    def _preemptor(name: str, drop: _ListIn, window: list[_Input]) -> str | None:
        """The behavior that appeared with the drop: in the same list, else the nearest
        later one, else the nearest earlier one."""
        same = [n for n in drop.appeared if n != name]
        if same:
            return same[0]
        lists = [i for i in window if isinstance(i, _ListIn) and i is not drop]
        later = [i for i in lists if i.time_ns >= drop.time_ns]
        earlier = [i for i in reversed(lists) if i.time_ns < drop.time_ns]
        for candidate in (*later, *earlier):
            names = [n for n in candidate.appeared if n != name]
            if names:
                return names[0]
        return None

    def _drop_of(self, name: str, time_ns: int) -> _ListIn | None:
        g = self.grace
        for item in self._window(time_ns - g, time_ns + g):
            if isinstance(item, _ListIn) and name in item.dropped:
                return item
        return None

    def _consume(self, kind: str, name: str, time_ns: int) -> bool:
        """Is there a carried command of `kind` for `name` shortly before `time_ns`?"""
        for item in self._window(time_ns - self.grace, time_ns):
            if (
                isinstance(item, _CommandIn)
                and not item.consumed
                and item.kind == kind
                and item.command.name == name
            ):
                item.consumed = True
                return True
        return False

    # -- decisions ---------------------------------------------------------------------------
    def _decide_list(self, item: _ListIn) -> None:
        t = item.time_ns
        for name in item.dropped:
            act = self._acts.get(name)
            if act is None or act.ended or act.inhibited:
                continue
            drop = self._classify(name, item)
            if drop.kind == "preempted":
                act.detail = PREEMPTED_BY.format(drop.by)
                continue
            if drop.kind == "ended":
                continue
            evidence = (
                "left the active list without an end event"
                if drop.event is None
                else "INTERRUPTED with no activation around it"
            )
            self._inhibit(act, t, evidence)
            if drop.event is None:
                self._end(act, t, EventCode.INTERRUPTED, INHIBITED, synthetic=True)
            else:
                act.detail = INHIBITED
        for name in item.appeared:
            act = self._acts.get(name)
            if act is not None and not act.in_list and t - act.start_ns <= self.grace:
                act.in_list = True  # reconstructed from its event a moment ago
                continue
            if act is not None and not act.ended:
                act.ended = True  # re-activated before its end event came: drop it
            victims = self._victims(name, item)
            arguments = self._arguments(item.arguments.get(name, ""))
            new = self._activate(name, t, arguments, "appeared in the active list", victims)
            new.in_list = True
        if item.names != self._written_list:
            self._written_list = item.names
            self._emit(t, LIST, {"behaviors": list(item.names)})

    def _victims(self, name: str, appearance: _ListIn) -> list[str]:
        g = self.grace
        victims: list[str] = []
        for item in self._window(appearance.time_ns - g, appearance.time_ns + g):
            if not isinstance(item, _ListIn):
                continue
            for dropped in item.dropped:
                act = self._acts.get(dropped)
                if act is None or dropped in victims:
                    continue
                if act.start_ns > item.time_ns:
                    continue  # the drop was of an earlier activation
                drop = self._classify(dropped, item)
                if drop.kind == "preempted" and drop.by == name:
                    victims.append(dropped)
        return victims

    def _decide_event(self, item: _EventIn) -> None:
        t = item.time_ns
        event = item.event
        self.stats.events += 1
        act = self._acts.get(event.name)
        if act is not None and act.ended:
            late = act.synthetic_end and act.end_ns is not None
            if late and t - act.end_ns <= LATE_EVENT_GRACES * self.grace:  # type: ignore[operator]
                # The real end of an activation already closed as inhibited: one end
                # event per activation, so it stays in the raw channel only.
                self.stats.late_events += 1
                return
            act = None
        if act is None:
            act = self._activate(event.name, t, {}, "ended without showing in the active list", [])
        detail = event.detail or act.detail
        if event.code is EventCode.INTERRUPTED and not detail:
            drop = self._drop_of(event.name, t)
            if drop is not None:
                kind = self._classify(event.name, drop)
                if kind.kind == "preempted":
                    detail = PREEMPTED_BY.format(kind.by)
                elif kind.kind == "inhibited":
                    detail = INHIBITED
                    if not act.inhibited:  # the command came before its event
                        self._inhibit(act, t, "INTERRUPTED with no activation around it")
        if event.code is None:
            self.stats.unknown_codes[event.raw_code] += 1
            act.ended, act.end_ns = True, t
            return
        self._end(act, t, event.code, detail, synthetic=False, event=event)

    def _decide_command(self, item: _CommandIn) -> None:
        data: dict[str, Any] = {"command": item.kind, "behavior": item.command.name}
        if item.kind == ACTIVATE:
            data["arguments"] = self._arguments(item.command.arguments)
        self._emit(item.time_ns, COMMAND, data)

    # -- outputs -----------------------------------------------------------------------------
    def _arguments(self, text: str) -> dict[str, Any]:
        parsed = parse_arguments(text)
        if parsed is None:
            self.stats.bad_arguments += 1
            return {}
        return parsed

    def _activate(
        self, name: str, t: int, arguments: dict[str, Any], evidence: str, victims: list[str]
    ) -> _Activation:
        self._uid += 1
        act = _Activation(self._uid, name, t, in_list=False)
        self._acts[name] = act
        if not self._consume(ACTIVATE, name, t):
            self.stats.activations += 1
            self._emit(
                t,
                COMMAND,
                {
                    "command": ACTIVATE,
                    "behavior": name,
                    "arguments": arguments,
                    "reconstructed": True,
                    "evidence": evidence,
                },
            )
        self.stats.preemptions += len(victims)
        self._emit(
            t,
            ACTIVATE,
            {
                "caller": "mission",
                "service": ACTIVATE,
                "request": {"behavior": name, "arguments": arguments},
                "response": {"ok": True, "error": "", "uid": act.uid, "preempted": victims},
                "reconstructed": True,
            },
            call=True,
        )
        return act

    def _inhibit(self, act: _Activation, t: int, evidence: str) -> None:
        act.inhibited = True
        if not self._consume(INHIBIT, act.name, t):
            self.stats.inhibitions += 1
            self._emit(
                t,
                COMMAND,
                {
                    "command": INHIBIT,
                    "behavior": act.name,
                    "reconstructed": True,
                    "evidence": evidence,
                },
            )
        self._emit(
            t,
            INHIBIT,
            {
                "caller": "mission",
                "service": INHIBIT,
                "request": {"behavior": act.name},
                "response": {"ok": True, "error": ""},
                "reconstructed": True,
            },
            call=True,
        )

    def _end(
        self,
        act: _Activation,
        t: int,
        code: EventCode,
        detail: str,
        *,
        synthetic: bool,
        event: Event | None = None,
    ) -> None:
        act.ended, act.end_ns, act.synthetic_end = True, t, synthetic
        data = self._event_data(act, code, event, detail)
        if synthetic:
            self.stats.synthetic_events += 1
            data["reconstructed"] = True
        self._emit(t, EVENT, data)

    @staticmethod
    def _event_data(
        act: _Activation, code: EventCode, event: Event | None, detail: str
    ) -> dict[str, Any]:
        data: dict[str, Any] = {
            "name": act.name,
            "uid": act.uid,
            "code": code.value,
            "detail": detail,
        }
        if event is not None and event.bag_uid:
            data["bag_uid"] = event.bag_uid
        return data
