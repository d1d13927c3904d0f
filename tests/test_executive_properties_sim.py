"""The executive's property tests again, with the real parts: the simulator (with
failures that strike at drawn times), the standard behavior library and the recorder.

`test_executive_properties` drives random command sequences through a `NullVehicle` and
generic behaviors, which keeps its expectations exact. Here the same machine (and all its
invariants: compatible active behaviors, reference counts, no conflicting capabilities,
processes iff needed, one end event per activation, published lists) runs the standard
library on `SimVehicle` in worlds whose battery may run out or whose motor may seize,
with every session recorded. What the standard behaviors add may change an answer: a
situation check may refuse what the catalog allows, `on_start` may fail, a behavior ends
when it ends. So the rules check what must hold anyway, plus:

* a behavior never runs on while the vehicle reports a fault that defeats its goal, and
  never reports GOAL_ACHIEVED with one (with an empty battery, only LAND, WAIT and
  BROADCAST_MESSAGE may: this test's own table);
* a failure ending (anything but GOAL_ACHIEVED and INTERRUPTED) names the vehicle's
  fault when there is one;
* the recording, read back, holds exactly the session's behavior events and service
  calls, and is complete.
"""

from __future__ import annotations

import dataclasses
import tempfile
from pathlib import Path
from typing import Any

from hypothesis import settings
from hypothesis import strategies as st
from hypothesis.stateful import initialize, rule
from test_executive_properties import (
    DEFAULT,
    MACHINE_SETTINGS,
    UNKNOWN_NAMES,
    ExecutiveMachine,
    _state,
    arguments_for,
)

from aeroexec.behaviors import STANDARD_LIBRARY
from aeroexec.executive import EventCode, Executive
from aeroexec.executive.messages import ServiceCallRecord
from aeroexec.recording import Recorder, open_recording
from aeroexec.recording.reader import RecordedCall, RecordedTopic
from aeroexec.vehicles.sim import SimVehicle
from aeroexec.vehicles.world import RandomFailure, ScheduledFailure, default_world

FAILURES = ("stuck_motor", "low_battery")
#: Goals an empty battery (a forced landing) leaves possible: landing, and what needs no
#: vehicle. Every other standard behavior must not report GOAL_ACHIEVED then.
STILL_POSSIBLE_WHEN_EMPTY = {"LAND", "WAIT", "BROADCAST_MESSAGE"}


@st.composite
def worlds(draw: st.DrawFn) -> Any:
    world = default_world()
    if draw(st.booleans(), label="short battery"):
        # 0.1-0.5 % of a 20-minute battery: 1-6 s of flight, 7-36 s on the ground.
        battery = dataclasses.replace(world.battery, initial=draw(st.floats(0.001, 0.005)))
        world = dataclasses.replace(world, battery=battery)
    failures = []
    if draw(st.booleans(), label="scheduled failure"):
        at = draw(st.floats(0.2, 5.0), label="at")
        failures.append(ScheduledFailure(draw(st.sampled_from(FAILURES)), at, 0.01))
    random_failure = None
    if draw(st.booleans(), label="random failure"):
        random_failure = RandomFailure(
            draw(st.sampled_from(FAILURES)), draw(st.floats(0.05, 1.0)), draw(st.integers(0, 99))
        )
    return dataclasses.replace(world, failures=tuple(failures), random_failure=random_failure)


class SimulatedMachine(ExecutiveMachine):
    catalogs = st.just(DEFAULT)  # the catalog the standard library implements

    @initialize(data=st.data())
    def build(self, data: st.DataObject) -> None:
        self.catalog = DEFAULT
        self.observed = True
        world = data.draw(worlds(), label="world")
        self.vehicle = SimVehicle(world, seed=data.draw(st.integers(0, 9), label="seed"))
        self.folder = tempfile.TemporaryDirectory()
        self.path = Path(self.folder.name) / "session.mcap"
        self.recorder = Recorder(self.path)
        self.ex = Executive(
            self.catalog,
            vehicle=self.vehicle,
            library=STANDARD_LIBRARY,
            observers=[self.observer, self.recorder],
        )
        assert self.ex.initiation.ok, self.ex.initiation.error
        # Take off first, mostly, so flying behaviors get their chance (refused on a low
        # battery).
        take_off = data.draw(st.integers(0, 3), label="take off") > 0
        if take_off and self.ex.activate_behavior("TAKE_OFF").ok:
            self.last_uid = 1
            self.started_ns[1] = self.ex.clock.now_ns()

    @rule(data=st.data())
    def activate(self, data: st.DataObject) -> None:
        ex = self.executive
        known = st.sampled_from(list(self.catalog.behaviors))
        name = data.draw(st.one_of(known, known, known, st.sampled_from(UNKNOWN_NAMES)))
        args = data.draw(arguments_for(self.catalog.behaviors.get(name)), label="arguments")
        expected_ok, expected_victims = self.expected_activation(name, args)
        before = _state(ex)
        victim_uids = {v: self.active_uids()[v] for v in expected_victims}
        events_before = len(ex.events)
        mark = len(self.observer.records)
        result = ex.activate_behavior(name, args)
        if not result.ok:
            # The catalog may allow what the behavior's situation check refuses (not
            # flying, battery low...), never the other way round.
            if expected_ok:
                assert result.error.startswith(f"{name}: "), result.error
            assert _state(ex) == before, "a rejected activation changed the executive"
            assert self.topics_since(mark) == [], "a rejected activation published"
            return
        assert expected_ok, (name, args, "accepted what the catalog forbids")
        uid = result.payload["uid"]
        assert uid == self.last_uid + 1
        self.last_uid = uid
        self.started_ns[uid] = ex.clock.now_ns()
        assert result.payload["preempted"] == expected_victims
        ended = [(e.name, e.uid, e.code) for e in ex.events[events_before:]]
        victims = [(v, victim_uids[v], EventCode.INTERRUPTED) for v in expected_victims]
        assert ended[: len(victims)] == victims
        # A behavior whose on_start fails ends at once, inside its own activation.
        assert ended[len(victims) :] in ([], [(name, uid, EventCode.PROCESS_FAILURE)])

    @rule(ticks=st.integers(1, 30))
    def step(self, ticks: int) -> None:
        ex = self.executive
        for _ in range(ticks):
            events_before = len(ex.events)
            ex.step()
            now = ex.clock.now_ns()
            fault = self.vehicle.state().fault
            for event in ex.events[events_before:]:
                assert event.time_ns == now
                assert event.uid in self.started_ns
                behavior = ex.behaviors[event.name]
                descriptor = self.catalog.behaviors[event.name]
                if descriptor.recurrent:
                    assert event.code is not EventCode.GOAL_ACHIEVED, event
                defeated = bool(fault) and fault.startswith(behavior.fails_on_faults)
                if fault == "battery_empty" and event.name not in STILL_POSSIBLE_WHEN_EMPTY:
                    defeated = True  # this test's own table, not the behaviors' lists
                if defeated:
                    assert event.code is not EventCode.GOAL_ACHIEVED, (event, fault)
                if fault and event.code not in (EventCode.GOAL_ACHIEVED, EventCode.INTERRUPTED):
                    assert fault in event.detail, (event, fault)
            for name in ex.active_behaviors:
                defeats = ex.behaviors[name].fails_on_faults
                assert not (fault and fault.startswith(defeats)), (name, fault)

    def teardown(self) -> None:
        if getattr(self, "ex", None) is None:
            return
        self.recorder.close()
        try:
            recording = open_recording(self.path)
            assert recording.complete, recording.problem
            events = [
                (r.data["name"], r.data["uid"], r.data["code"], r.data["detail"])
                for r in recording.records()
                if isinstance(r, RecordedTopic) and r.name == "behavior_event"
            ]
            assert events == [(e.name, e.uid, e.code.value, e.detail) for e in self.ex.events]
            calls = [r.seq for r in recording.records() if isinstance(r, RecordedCall)]
            seen = [r.seq for r in self.observer.records if isinstance(r, ServiceCallRecord)]
            assert calls == seen
        finally:
            self.folder.cleanup()


TestSimulatedStandardLibrary = SimulatedMachine.TestCase
TestSimulatedStandardLibrary.settings = settings(MACHINE_SETTINGS, max_examples=40)
