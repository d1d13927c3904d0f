"""Properties monitored while a session runs (`run --spec`, `fly --spec`).

`PropertyMonitor` is a bus observer. It feeds the session's messages to the same
`SignalBuilder` a recording's are fed to offline (`check.py`), and at the end evaluates
the same properties with the same code: online and offline verdicts of one flight are
identical by construction, and `tests/test_properties_online.py` checks they are.

During the session it judges the properties that can act (those with an `action`) as
soon as their verdict on a tick is final. A tick is judged when it is over: when the
first message of a later tick arrives (a mission command comes after the tick's vehicle
state), so each sample is the one `check` sees. The body of `always(body)` reads a
bounded time around each tick (`Formula.window_ticks`):

* a body that reads only the present tick (`always(distance_home <= 50)`: no temporal
  operator) is judged at every tick, on that tick's values as Python floats
  (`semantics.instant`, the same Boolean semantics without arrays: a geofence costs
  about a microsecond a tick);
* any other body, and a tick the first way cannot judge (an arithmetic error, a value
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
from aeroexec.properties.signals import PERIOD_NS, PERIOD_S, SignalBuilder
from aeroexec.properties.spec import Property, PropertySet
from aeroexec.recording.schemas import PROPERTIES_TOPIC

#: How often (session seconds) properties with an action whose body looks beyond the
#: present tick are judged during a session.
CHECK_EVERY_S = 0.5
TOPIC = PROPERTIES_TOPIC


class PropertyMonitor:
    #: The bus topics and services signals come from (`Bus` calls it for no other): the
    #: session's other messages change no signal, and its last tick, which every message
    #: extends, holds a vehicle state or is the time the session ends at.
    reads = TOPICS | SERVICES

    def __init__(self, properties: PropertySet, *, check_every_s: float = CHECK_EVERY_S) -> None:
        self.properties = properties
        self.builder = SignalBuilder(None)
        self._every = max(1, round(check_every_s / PERIOD_S))
        #: Acting properties, each with (past, future) ticks.
        self._acting: list[tuple[Property, int, int]] = []
        #: Those judged tick by tick: the property and its body on one tick's values.
        self._instant: list[tuple[Property, Callable[[Sample], float]]] = []
        #: Per acting property, the last tick judged.
        self._judged: dict[str, int] = {}
        for prop in properties.properties:
            window = prop.formula.window_ticks()
            if prop.action and window is not None:
                self._acting.append((prop, *window))
                self._judged[prop.name] = -1
                body = prop.formula.instant_body
                if body is not None:
                    self._instant.append((prop, body))
        self._instant_names = tuple(
            dict.fromkeys(name for prop, _ in self._instant for name in prop.formula.signals)
        )
        #: The tick the last message fell in, and when the next one begins.
        self._open = -1
        self._next_tick_ns = 0 if self._acting else math.inf
        self._next_check = 0
        self._executive: Executive | None = None
        #: Violations seen during the session: property name -> first violating tick.
        self.early: dict[str, int] = {}
        #: The final verdicts (after `session_ending`).
        self.verdicts: list[Verdict] = []
        #: The violated property whose action ended the session (None: none did).
        self.stopped_by: Property | None = None
        self.stopped_at_s: float | None = None

    # -- the session ----------------------------------------------------------------------
    def session_started(self, executive: Executive) -> None:
        self._executive = executive
        self.builder.use_catalog(executive.catalog.conflicts_of)

    def session_ending(self, executive: Executive) -> None:
        # The verdicts below are recorded now: `check` counts their tick in the session.
        self.builder.mark_time(executive.clock.now_ns())
        self.verdicts = evaluate(self.properties, self.builder.finish())
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
            self.builder.call(record.service, t_ns, record.request, record.response)
        else:  # a bus that calls it for every message
            self.builder.mark_time(t_ns)

    def on_topic(self, record: TopicRecord) -> None:
        topic = record.topic
        if topic == TOPIC:
            return
        t_ns = record.log_time_ns
        if t_ns >= self._next_tick_ns:
            self._ticks_over(t_ns)
        if topic in TOPICS:
            self.builder.topic(topic, t_ns, record.data)
        else:  # a bus that calls it for every message
            self.builder.mark_time(t_ns)

    # -- internals ------------------------------------------------------------------------
    def _ticks_over(self, t_ns: int) -> None:
        """A message of a later tick: every tick before it is over, judge them (before
        this message is fed: the builder holds the state at the end of the last one)."""
        tick = t_ns // PERIOD_NS
        self._next_tick_ns = (tick + 1) * PERIOD_NS
        first, done, self._open = self._open, tick - 1, tick
        if done < 0 or self.stopped_by is not None:
            return
        if self._instant:
            for over in range(max(first, 0), done + 1):
                if self._judge_instant(over):
                    return
        if done >= self._next_check:
            self._next_check = done + self._every
            self._judge(done)

    def _judge_instant(self, tick: int) -> bool:
        """Judge `tick` for each property judged tick by tick and judged up to the tick
        before (the others catch up on arrays); True when one is violated."""
        latest = self.builder.latest
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
            columns = self.builder.window(start, prop.formula.signals, now)
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
