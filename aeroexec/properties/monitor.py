"""Properties monitored while a session runs (`run --spec`, `fly --spec`).

`PropertyMonitor` is a bus observer. It feeds the session's messages to the same
`SignalBuilder` a recording's are fed to offline (`check.py`), and at the end evaluates
the same properties with the same code: online and offline verdicts of one flight are
identical by construction, and `tests/test_properties_online.py` checks they are.

Vehicle states, one a tick, are fed in batches (`STATES_AT_ONCE`, and whenever the
signals are read): the builder's work on them is the same, done in a loop that stays
in the processor's caches instead of once a tick between the simulator's own work
(about 3 ms less of a 10-minute patrol's 15, measured). The other messages, rare, are
fed as they come: they change other signals than the states do, so the order between
the two is kept where it matters.

During the session it judges the properties that can act (those with an `action`) as
soon as their verdict on a tick is final. A tick is judged when it is over: when the
first message of a later tick arrives (a mission command comes after the tick's vehicle
state), so each sample is the one `check` sees. The body of `always(body)` reads a
bounded time around each tick (`Formula.window_ticks`):

* a vehicle signal against a number (`always(distance_home <= 50)`, a ceiling, a
  battery floor: `Formula.threshold`) is judged on each vehicle state as it comes, on
  the state itself (`signals.state_holds`, the same floats): a tick's verdict is that of
  its last state, so while every state keeps it nothing else is needed. It is judged
  so once the first state is known and the ticks so far have been judged the next way
  (before its first state, a vehicle signal holds the first state's value); a state
  that breaks it (or cannot be judged on floats) has it judged the next way from that
  state's tick on, until that has caught up again;
* any other body that reads only the present tick is judged at every tick when it is
  over, on that tick's values as Python floats (`semantics.instant`, the same Boolean
  semantics without arrays);
* any other body, and a tick the ways above cannot judge (an arithmetic error, a value
  not known yet), at each check (every `check_every_s` of session time), on the window
  of ticks that became final since the last one, with the history the body needs.

On the first violation it publishes the verdict (the `properties` channel, and an ERROR
line on `log`) and asks the executive to stop; the session ends the flight with the
property's action (`aeroexec.mission.assurance`, or the live ending). Properties without
an action are judged once, at the end, and their violations published then.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from aeroexec.executive.executive import Executive
from aeroexec.executive.messages import ServiceCallRecord, TopicRecord
from aeroexec.properties.check import SERVICES, TOPICS, VIOLATED, Verdict, evaluate
from aeroexec.properties.semantics import Sample
from aeroexec.properties.signals import (
    PERIOD_NS,
    PERIOD_S,
    ROW_SIGNALS,
    Row,
    SignalBuilder,
    state_holds,
)
from aeroexec.properties.spec import Property, PropertySet
from aeroexec.recording.schemas import PROPERTIES_TOPIC

#: How often (session seconds) properties with an action whose body looks beyond the
#: present tick are judged during a session.
CHECK_EVERY_S = 0.5
#: Vehicle states kept before they are fed to the builder together (6.4 s of a
#: simulated session; a few tens of kB).
STATES_AT_ONCE = 64
TOPIC = PROPERTIES_TOPIC
#: A test of a vehicle state (`signals.state_holds`).
StateTest = Callable[[dict[str, Any]], bool]
#: A property judged by row: (property, signal, test, bound), `Formula.threshold`.
ByRow = tuple[Property, str, Callable[[float, float], bool], float]
#: What a state test raises on a state that is not numbers, or is malformed.
_UNJUDGED = (ArithmeticError, LookupError, TypeError, ValueError, AttributeError)


class PropertyMonitor:
    #: The bus topics and services signals come from (`Bus` calls it for no other): the
    #: session's other messages change no signal, and its last tick, which every message
    #: extends, holds a vehicle state or is the time the session ends at.
    reads = TOPICS | SERVICES

    def __init__(self, properties: PropertySet, *, check_every_s: float = CHECK_EVERY_S) -> None:
        self.properties = properties
        self._builder = SignalBuilder(None)
        #: Vehicle states not fed yet (`_feed_states`).
        self._states: list[TopicRecord] = []
        self._every = max(1, round(check_every_s / PERIOD_S))
        #: Every acting property, with (past, future) ticks, in file order.
        self._all_acting: list[tuple[Property, int, int]] = []
        #: Those that can be judged as each vehicle state comes: a vehicle signal against
        #: a number, (property, signal, test, bound); and those judged so now (`_by_row_on`).
        self._row_able: list[ByRow] = []
        self._by_row: list[ByRow] = []
        #: Per acting property, the last tick judged (one judged by row: when it left
        #: that way, the tick before).
        self._judged: dict[str, int] = {}
        for prop in properties.properties:
            window = prop.formula.window_ticks()
            if prop.action and window is not None:
                self._all_acting.append((prop, *window))
                self._judged[prop.name] = -1
                threshold = prop.formula.threshold
                if threshold is not None and threshold[0] in ROW_SIGNALS:
                    self._row_able.append((prop, *threshold))
        #: The others, judged when ticks are over: on arrays, and those of the present
        #: tick also tick by tick (the property and its body on one tick's values).
        self._acting: list[tuple[Property, int, int]] = []
        self._instant: list[tuple[Property, Callable[[Sample], float]]] = []
        self._instant_names: tuple[str, ...] = ()
        self._group()
        #: Their tests on a state, one each (which a state broke), and all in one call
        #: (None: none is judged by row).
        self._state_tests: list[tuple[Property, StateTest]] = []
        self._state_holds: StateTest | None = None
        #: The tick the last message fell in (kept while ticks are judged as they end),
        #: and the start of the tick whose first message has them judged.
        self._open = -1
        self._next_tick_ns: float = 0 if self._acting else math.inf
        self._next_check = 0
        self._executive: Executive | None = None
        #: Violations seen during the session: property name -> first violating tick.
        self.early: dict[str, int] = {}
        #: The final verdicts (after `session_ending`).
        self.verdicts: list[Verdict] = []
        #: The violated property whose action ended the session (None: none did).
        self.stopped_by: Property | None = None
        self.stopped_at_s: float | None = None

    def _group(self) -> None:
        """The acting properties not judged by row: on arrays, and tick by tick."""
        by_row = {prop.name for prop, *_ in self._by_row}
        self._acting = [entry for entry in self._all_acting if entry[0].name not in by_row]
        self._instant = [
            (prop, body)
            for prop, _, _ in self._acting
            if (body := prop.formula.instant_body) is not None
        ]
        self._instant_names = tuple(
            dict.fromkeys(name for prop, _ in self._instant for name in prop.formula.signals)
        )

    @property
    def builder(self) -> SignalBuilder:
        """The signal builder, fed every message so far."""
        self._feed_states()
        return self._builder

    # -- the session ----------------------------------------------------------------------
    def session_started(self, executive: Executive) -> None:
        self._executive = executive
        self.builder.use_catalog(executive.catalog.conflicts_of)

    def session_ending(self, executive: Executive) -> None:
        builder = self.builder
        # The verdicts below are recorded now: `check` counts their tick in the session.
        builder.mark_time(executive.clock.now_ns())
        self.verdicts = evaluate(self.properties, builder.finish())
        for verdict in self.verdicts:
            if verdict.status == VIOLATED and verdict.name not in self.early:
                self._publish(executive, verdict.property, verdict, None)
        for verdict in self.verdicts:
            executive.bus.publish(TOPIC, _final(verdict))

    # -- BusObserver ----------------------------------------------------------------------
    def on_service_call(self, record: ServiceCallRecord) -> None:
        t_ns = record.log_time_ns
        if t_ns >= self._next_tick_ns:
            self._ticks_over(t_ns)
        if record.service in SERVICES:
            self._builder.call(record.service, t_ns, record.request, record.response)
        else:  # a bus that calls it for every message
            self._builder.mark_time(t_ns)

    def on_topic(self, record: TopicRecord) -> None:
        topic = record.topic
        t_ns = record.log_time_ns
        if topic == "vehicle/state":  # a state per tick: the hot path, in few steps
            if t_ns >= self._next_tick_ns:
                self._ticks_over(t_ns)
            states = self._states
            states.append(record)
            holds = self._state_holds
            if holds is not None:  # judge the properties judged by row on it, in one call
                try:
                    kept = holds(record.data)
                except _UNJUDGED:
                    kept = False
                if not kept:
                    self._state_broke(record)
            if len(states) >= STATES_AT_ONCE:
                self._feed_states()
            return
        if topic == TOPIC:
            return
        if t_ns >= self._next_tick_ns:
            self._ticks_over(t_ns)
        if topic in TOPICS:
            self._builder.topic(topic, t_ns, record.data)
        else:  # a bus that calls it for every message
            self._builder.mark_time(t_ns)

    # -- internals ------------------------------------------------------------------------
    def _feed_states(self) -> None:
        """Feed the builder the vehicle states kept so far."""
        states = self._states
        if states:
            self._builder.vehicle_states(states)
            states.clear()

    def _ticks_over(self, t_ns: int) -> None:
        """A message of a later tick: every tick before it is over, judge them (before
        this message is fed: the builder holds the state at the end of the last one)."""
        self._feed_states()
        tick = t_ns // PERIOD_NS
        first, done, self._open = self._open, tick - 1, tick
        self._next_tick_ns = self._next_call(tick)
        if done < 0 or self.stopped_by is not None:
            return
        if self._instant:
            for over in range(max(first, 0), done + 1):
                if self._judge_instant(over):
                    return
        if done >= self._next_check:
            self._next_check = done + self._every
            self._next_tick_ns = self._next_call(tick)
            self._judge(done)
        if len(self._by_row) < len(self._row_able) and self.stopped_by is None:
            self._by_row_on(done)
            self._next_tick_ns = self._next_call(tick)

    def _next_call(self, tick: int) -> float:
        """When the next message must have ticks judged: at the next tick while some are
        judged tick by tick, at the tick after the next check while some are judged only
        on arrays; never while all are judged by row (a state that breaks one sends it
        here, `_state_broke`)."""
        if self._instant:
            return (tick + 1) * PERIOD_NS
        if self._acting:
            return (max(tick, self._next_check) + 1) * PERIOD_NS
        return math.inf

    def _by_row_on(self, done: int) -> None:
        """Judge by row, from the next state on, the properties that can be and are
        judged up to `done` (the tick before the message being fed), once there is a
        first state: its tick's verdict (and before it, where the first state counts)
        is given the way ticks over are judged, which is the definition; from there on
        a tick's verdict is that of its last state."""
        first = self._builder.home_row
        if first is None:
            return
        on = {prop.name for prop, *_ in self._by_row}
        on |= {prop.name for prop, *_ in self._row_able if self._judged[prop.name] >= done}
        if len(on) == len(self._by_row):
            return
        self._by_row = [entry for entry in self._row_able if entry[0].name in on]
        self._state_tests = self._tests_on(first)
        self._state_holds = self._all_hold(first)
        self._group()

    def _state_broke(self, record: TopicRecord) -> None:
        """A vehicle state broke properties judged by row (or cannot be judged on floats,
        or has fields an import only guessed: as `latest`, not judged here). Their
        verdict at a tick is that of the tick's last state: those it broke are judged
        from its tick on when ticks are over, as any other; by then a later state of
        that tick may keep them."""
        state = record.data
        broken = [prop for prop, holds in self._state_tests if not _holds(holds, state)]
        self._by_row_off(broken, record.log_time_ns // PERIOD_NS)

    def _tests_on(self, first: Row) -> list[tuple[Property, StateTest]]:
        """Each property judged by row with its own test (which ones a state broke),
        `first` the first state's row."""
        return [
            (prop, state_holds([(signal, test, bound)], first))
            for prop, signal, test, bound in self._by_row
        ]

    def _all_hold(self, first: Row) -> StateTest | None:
        """One test of every property judged by row (None: none is)."""
        if not self._by_row:
            return None
        return state_holds(
            [(signal, test, bound) for _, signal, test, bound in self._by_row], first
        )

    def _by_row_off(self, props: list[Property], tick: int) -> None:
        """Judge `props` from `tick` on with the others, when ticks are over (every tick
        before it held: each of their last states kept them); they come back to be
        judged by row once judged up to date (`_by_row_on`)."""
        names = {prop.name for prop in props}
        self._by_row = [entry for entry in self._by_row if entry[0].name not in names]
        self._state_tests = [e for e in self._state_tests if e[0].name not in names]
        # Judged by row only once the first state (home) is known: it still is.
        first = self._builder.home_row
        assert first is not None
        self._state_holds = self._all_hold(first)
        for name in names:
            self._judged[name] = tick - 1
        self._group()
        # `tick` is the last message's: have it judged when the next tick's first comes.
        self._open = tick
        self._next_tick_ns = min(self._next_tick_ns, (tick + 1) * PERIOD_NS)

    def _judge_instant(self, tick: int) -> bool:
        """Judge `tick` for each property judged tick by tick and judged up to the tick
        before (the others catch up on arrays); True when one is violated."""
        latest = self._builder.latest
        shared = latest(self._instant_names, tick)
        judged = self._judged
        for prop, body in self._instant:
            if judged[prop.name] != tick - 1:
                continue
            values = shared if shared is not None else latest(prop.formula.signals, tick)
            if values is None:
                continue
            try:
                verdict = body(values)
            except (ArithmeticError, ValueError):
                continue  # numpy's inf or nan: judged on arrays at the next check
            judged[prop.name] = tick
            if verdict < 0:
                self._violated(prop, tick)
                return True
        return False

    def _judge(self, now: int) -> None:
        """Judge, on arrays, every tick up to `now` whose verdict is final."""
        for prop, past, future in self._acting:
            judged = self._judged[prop.name]
            final = now - future
            if final <= judged:
                continue
            start = max(0, judged + 1 - past)
            columns = self._builder.window(start, prop.formula.signals, now)
            self._judged[prop.name] = final
            if columns is None:
                continue  # judged at the end, where a missing signal is reported
            body = prop.formula.body_verdicts(columns, now + 1 - start)
            bad = (body[judged + 1 - start : final + 1 - start] < 0).nonzero()[0]
            if len(bad):
                self._violated(prop, judged + 1 + int(bad[0]))
                return

    def _violated(self, prop: Property, tick: int) -> None:
        self.early[prop.name] = tick
        self.stopped_by = prop
        self.stopped_at_s = round(tick * PERIOD_S, 6)
        executive = self._executive
        if executive is not None:
            self._publish(executive, prop, None, tick)
            assert prop.action is not None
            executive.request_stop(
                f"property {prop.name} violated at {tick * PERIOD_S:.2f} s "
                f"({prop.where}): {prop.action}",
                prop.action,
            )

    def _publish(
        self, executive: Executive, prop: Property, verdict: Verdict | None, tick: int | None
    ) -> None:
        if verdict is not None and verdict.interval_s is not None:
            start_s, end_s = verdict.interval_s
        else:
            start_s = end_s = round((tick or 0) * PERIOD_S, 6)
        what = prop.description or prop.formula.text
        action = f"; {prop.action}" if prop.action and verdict is None else ""
        message = f"property {prop.name} violated at {start_s:.2f} s: {what}{action}"
        data: dict[str, Any] = {
            "property": prop.name,
            "status": VIOLATED,
            "severity": prop.severity,
            "t_s": start_s,
            "end_s": end_s,
            "defined_at": prop.where,
            "message": message,
        }
        if prop.action:
            data["action"] = prop.action
        executive.bus.publish(TOPIC, data)
        level = {"error": "ERROR", "warning": "WARNING"}.get(prop.severity, "INFO")
        executive.log(message, level, f"property:{prop.name}")


def _holds(holds: StateTest, state: dict[str, Any]) -> bool:
    """Whether a state test keeps its property on `state` (False too where it cannot be
    judged on floats)."""
    try:
        return holds(state)
    except _UNJUDGED:
        return False


def _final(verdict: Verdict) -> dict[str, Any]:
    prop = verdict.property
    data: dict[str, Any] = {
        "property": prop.name,
        "status": verdict.status,
        "severity": prop.severity,
        "defined_at": prop.where,
        "message": verdict.message(),
    }
    if verdict.interval_s is not None:
        data["t_s"], data["end_s"] = verdict.interval_s
    if verdict.robustness is not None and math.isfinite(verdict.robustness):
        data["robustness"] = verdict.robustness + 0.0
    return data
