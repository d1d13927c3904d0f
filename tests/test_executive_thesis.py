"""The thesis' own validation list (section 4.2.1), as executable tests.

Fifteen component tests (4 behavior process, 4 coordinator, 4 specialist, 3 resource
manager) and the four integration tests of its table (behaviors activated, behaviors
stopped, belief manager integration, error management), plus the repairs
docs/design.md#the-repairs-of-the-thesis makes to the thesis: nothing half-done on a
rejected activation, the zero-reference bug fixed, recurrent behaviors never time out,
author exceptions never escape into the core.

Everything runs on `NullVehicle` with behaviors that are either `GenericBehavior` (what
the executive builds for a catalog behavior without an implementation) or the small
`probe` subclasses below, which journal every hook call.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
import yaml

from aeroexec.catalog import DEFAULT_CATALOG, THESIS_CATALOG, Catalog, load_catalog, parse_catalog
from aeroexec.executive import (
    Behavior,
    BehaviorEvent,
    Beliefs,
    EventCode,
    Executive,
    Finished,
    MemoryObserver,
    ServiceCallRecord,
    Situation,
    TopicRecord,
)
from aeroexec.executive.behavior import GenericBehavior
from aeroexec.vehicles.base import VehicleState
from aeroexec.vehicles.null import NullVehicle

DEFAULT = load_catalog(DEFAULT_CATALOG)
THESIS = load_catalog(THESIS_CATALOG)

ODOMETRY = "SELF_LOCALIZATION_BY_ODOMETRY"
SETPOINT = "SETPOINT_BASED_FLIGHT_CONTROL"
PATH = "PATH_PLANNING"
SERVOING = "VISUAL_SERVOING"
MARKERS = "VISUAL_MARKERS_RECOGNITION"
GO_TO = {"coordinates": [1.0, 2.0, 3.0]}

#: A small catalog for the cases the default one cannot show: a capability conflict
#: between behaviors that do not preempt each other, a recurrent behavior with a
#: timeout, a goal-based one with a short timeout, a default capability a behavior
#: also needs, and a process shared by two capabilities.
SMALL_CATALOG = """
behavior_descriptors:
  - behavior: MOVE
    timeout: 30
    recurrent: no
    incompatible_lists: [motion]
    capabilities: [PATH_PLANNING]
  - behavior: HOLD
    recurrent: yes
    capabilities: [SETPOINT_CONTROL]
  - behavior: TRACK
    timeout: 30
    recurrent: no
    incompatible_lists: [motion]
    capabilities: [VISUAL_SERVOING]
  - behavior: SLOW
    timeout: 0.5
    recurrent: no
  - behavior: WATCH
    timeout: 0.5
    recurrent: yes
    capabilities: [CAMERA, MAPPING]
behavior_lists:
  - list: motion
    behaviors: [MOVE, TRACK]
capability_descriptors:
  - capability: SETPOINT_CONTROL
    active_by_default: no
    processes: [controller]
    incompatible_capabilities: [VISUAL_SERVOING]
  - capability: PATH_PLANNING
    active_by_default: no
    processes: [planner]
  - capability: VISUAL_SERVOING
    active_by_default: no
    processes: [tracker, ibvs]
  - capability: CAMERA
    active_by_default: yes
    processes: [camera_driver]
  - capability: MAPPING
    active_by_default: no
    processes: [camera_driver, mapper]
"""
SMALL = parse_catalog(SMALL_CATALOG, "small.yaml")


# -- helpers ------------------------------------------------------------------------------
class Journal:
    """What the probes saw, in order; `ex` is set once the executive exists."""

    def __init__(self) -> None:
        self.entries: list[tuple[Any, ...]] = []
        self.ex: Executive | None = None

    def note(self, *entry: Any) -> None:
        self.entries.append(entry)

    def calls(self, hook: str, behavior: str | None = None) -> list[tuple[Any, ...]]:
        return [e for e in self.entries if e[0] == hook and (behavior is None or e[1] == behavior)]

    def references(self) -> dict[str, int]:
        assert self.ex is not None
        return self.ex.capability_references


def probe(
    name: str,
    journal: Journal,
    *,
    finish_after: float | None = None,
    code: EventCode = EventCode.GOAL_ACHIEVED,
    fail_in: tuple[str, ...] = (),
    situation: Callable[[Beliefs], Situation] | None = None,
    on_start: Callable[[Behavior, Mapping[str, Any]], None] | None = None,
) -> type[Behavior]:
    """A behavior that journals every hook (with the capability references it sees),
    ends with `code` after `finish_after` seconds, and raises in the hooks `fail_in`."""

    class Probe(Behavior):
        def check_situation(self, beliefs: Beliefs) -> Situation:
            journal.note("check_situation", self.behavior_name)
            if "check_situation" in fail_in:
                raise RuntimeError("boom in check_situation")
            return situation(beliefs) if situation else Situation(True)

        def on_start(self, args: Mapping[str, Any]) -> None:
            journal.note("on_start", self.behavior_name, dict(args), journal.references())
            if on_start is not None:
                on_start(self, args)
            if "on_start" in fail_in:
                raise RuntimeError("boom in on_start")

        def on_run(self) -> Finished | None:
            journal.note("on_run", self.behavior_name, self.elapsed)
            if "on_run" in fail_in:
                raise ValueError("boom in on_run")
            if finish_after is not None and self.elapsed >= finish_after:
                return Finished(code, "probe done")
            return None

        def on_stop(self) -> None:
            journal.note("on_stop", self.behavior_name, journal.references())
            if "on_stop" in fail_in:
                raise RuntimeError("boom in on_stop")

    Probe.name = name
    Probe.__qualname__ = f"Probe[{name}]"
    return Probe


def make(
    catalog: Catalog = DEFAULT,
    library: Mapping[str, type[Behavior]] | None = None,
    journal: Journal | None = None,
    vehicle: NullVehicle | None = None,
) -> tuple[Executive, MemoryObserver]:
    observer = MemoryObserver()
    ex = Executive(
        catalog,
        vehicle=vehicle if vehicle is not None else NullVehicle(),
        library=dict(library or {}),
        observers=[observer],
        stand_in=GenericBehavior,
    )
    if journal is not None:
        journal.ex = ex
    return ex, observer


@dataclass(frozen=True)
class Snapshot:
    """Everything an activation could change."""

    active: tuple[tuple[str, int], ...]
    running_behaviors: tuple[str, ...]
    references: tuple[tuple[str, int], ...]
    holders: tuple[tuple[str, tuple[str, ...]], ...]
    processes: tuple[str, ...]
    process_states: tuple[tuple[str, str], ...]
    events: tuple[BehaviorEvent, ...]


def snapshot(ex: Executive) -> Snapshot:
    res = ex.resources
    return Snapshot(
        active=tuple((n, ex.coordinator.active[n].uid) for n in ex.active_behaviors),
        running_behaviors=tuple(n for n, b in ex.behaviors.items() if b.running),
        references=tuple(sorted(res.references.items())),
        holders=tuple(sorted((c, tuple(h)) for c, h in res.holders.items())),
        processes=ex.running_processes,
        process_states=tuple(sorted((n, p.state.value) for n, p in res.processes.items())),
        events=tuple(ex.events),
    )


def topics_after(
    observer: MemoryObserver, mark: int, topic: str | None = None
) -> list[TopicRecord]:
    return [
        r
        for r in observer.records[mark:]
        if isinstance(r, TopicRecord) and (topic is None or r.topic == topic)
    ]


def process_changes(observer: MemoryObserver, mark: int = 0) -> list[tuple[str, str]]:
    return [
        (r.data["state"], r.data["process"]) for r in topics_after(observer, mark, "process_state")
    ]


def assert_rejected_cleanly(
    ex: Executive, observer: MemoryObserver, act: Callable[[], Any], *, error: str
) -> None:
    """`act` must fail with `error` in its message and change nothing at all."""
    before = snapshot(ex)
    mark = len(observer.records)
    result = act()
    assert not result.ok
    assert error in result.error
    assert snapshot(ex) == before
    assert topics_after(observer, mark) == [], "a rejected command published something"


def events_of(ex: Executive, uid: int) -> list[BehaviorEvent]:
    return [e for e in ex.events if e.uid == uid]


def file_entries(path: Path) -> dict[str, Any]:
    return yaml.safe_load(path.read_text(encoding="utf-8"))


# == Behavior process =====================================================================
def test_behavior_starts_capabilities_then_on_start() -> None:
    """Thesis 4.2.1, behavior process 1 -- "Behavior starts": the capabilities are sent
    (activated) and the author's on_start is called, with the validated arguments, after
    the capabilities are in place (Algorithm 3.2)."""
    journal = Journal()
    ex, observer = make(library={"GO_TO_POINT": probe("GO_TO_POINT", journal)}, journal=journal)
    result = ex.activate_behavior("GO_TO_POINT", {"coordinates": (1, 2.5, 3)})
    assert result.ok and result.payload["uid"] == 1
    [start] = journal.calls("on_start")
    _, _, args, refs_seen = start
    assert args == {"COORDINATES": [1, 2.5, 3]}  # the catalog's spelling, a list
    assert refs_seen == {ODOMETRY: 1, SETPOINT: 1, PATH: 1}
    assert ex.behaviors["GO_TO_POINT"].running
    assert ex.running_processes == (
        "droneOdometryStateEstimator",
        "droneTrajectoryController",
        "droneTrajectoryPlanner",
        "droneYawPlanner",
    )
    # The start service asked the resource manager, as the behavior, before on_start.
    [start_call] = observer.calls("behavior_go_to_point/start")
    [resources] = observer.calls("activate_resources")
    assert resources.caller == "behavior_go_to_point"
    assert resources.parent_seq == start_call.seq
    assert resources.request == {"behavior": "GO_TO_POINT"} and resources.response["ok"]


def test_behavior_stops_on_stop_then_capabilities_cancelled() -> None:
    """Thesis 4.2.1, behavior process 2 -- "Behavior stops": stopping calls on_stop
    (while the capabilities are still held, Algorithm 3.4) and then cancels the
    behavior's capabilities; its processes stop; on_run is never called again."""
    journal = Journal()
    ex, observer = make(library={"GO_TO_POINT": probe("GO_TO_POINT", journal)}, journal=journal)
    ex.activate_behavior("GO_TO_POINT", GO_TO)
    ex.run_for(0.3)
    runs = len(journal.calls("on_run"))
    assert runs == 3
    mark = len(observer.records)
    assert ex.inhibit_behavior("GO_TO_POINT").ok
    [stop] = journal.calls("on_stop")
    assert stop[2] == {ODOMETRY: 1, SETPOINT: 1, PATH: 1}  # on_stop ran before the cancel
    assert ex.capability_references == {ODOMETRY: 1}
    assert ex.running_processes == ("droneOdometryStateEstimator",)
    assert not ex.behaviors["GO_TO_POINT"].running
    assert process_changes(observer, mark) == [
        ("stopped", "droneYawPlanner"),
        ("stopped", "droneTrajectoryPlanner"),
        ("stopped", "droneTrajectoryController"),
    ]
    [cancel] = [
        r
        for r in observer.records[mark:]
        if isinstance(r, ServiceCallRecord) and r.service == "cancel_resources"
    ]
    assert cancel.caller == "behavior_go_to_point" and cancel.response["ok"]
    ex.run_for(1.0)
    assert len(journal.calls("on_run")) == runs
    assert len(journal.calls("on_stop")) == 1


def _interrupt_by_inhibit(ex: Executive) -> None:
    assert ex.inhibit_behavior("GO_TO_POINT").ok


def _interrupt_by_preemption(ex: Executive) -> None:
    assert ex.activate_behavior("ROTATE", {"angle": 90}).payload["preempted"] == ["GO_TO_POINT"]


def _interrupt_by_reactivation(ex: Executive) -> None:
    again = ex.activate_behavior("GO_TO_POINT", GO_TO)
    assert again.ok and again.payload == {"uid": 2, "preempted": ["GO_TO_POINT"]}


@pytest.mark.parametrize(
    ("options", "action", "code", "detail"),
    [
        pytest.param({"finish_after": 0.3}, None, EventCode.GOAL_ACHIEVED, "probe done", id="goal"),
        pytest.param(
            {"finish_after": 0.2, "code": EventCode.WRONG_PROGRESS},
            None,
            EventCode.WRONG_PROGRESS,
            "probe done",
            id="author-code",
        ),
        pytest.param(
            {"fail_in": ("on_start",)},
            None,
            EventCode.PROCESS_FAILURE,
            "on_start failed: RuntimeError: boom in on_start",
            id="on_start-raises",
        ),
        pytest.param(
            {"fail_in": ("on_run",)},
            None,
            EventCode.PROCESS_FAILURE,
            "on_run failed: ValueError: boom in on_run",
            id="on_run-raises",
        ),
        pytest.param(
            {"finish_after": 0.2, "fail_in": ("on_stop",)},
            None,
            EventCode.PROCESS_FAILURE,
            "on_stop failed: RuntimeError: boom in on_stop",
            id="on_stop-raises",
        ),
        pytest.param({}, _interrupt_by_inhibit, EventCode.INTERRUPTED, "inhibited", id="inhibit"),
        pytest.param(
            {}, _interrupt_by_preemption, EventCode.INTERRUPTED, "preempted by ROTATE", id="preempt"
        ),
        pytest.param(
            {},
            _interrupt_by_reactivation,
            EventCode.INTERRUPTED,
            "preempted by GO_TO_POINT",
            id="reactivate",
        ),
    ],
)
def test_events_are_sent_once_with_the_right_termination(
    options: dict[str, Any],
    action: Callable[[Executive], None] | None,
    code: EventCode,
    detail: str,
) -> None:
    """Thesis 4.2.1, behavior process 3 -- "Events are sent": one event only, with the
    correct termination (GOAL_ACHIEVED, an author's code, PROCESS_FAILURE from an
    exception in on_start/on_run/on_stop, INTERRUPTED on inhibit/preemption/restart);
    the behavior stops itself after it and leaves the active set."""
    journal = Journal()
    library = {"GO_TO_POINT": probe("GO_TO_POINT", journal, **options)}
    ex, observer = make(library=library, journal=journal)
    assert ex.activate_behavior("GO_TO_POINT", GO_TO).payload["uid"] == 1
    if action is not None:
        ex.step()
        action(ex)
    ex.run_for(3.0)
    [event] = events_of(ex, 1)
    assert (event.name, event.code, event.detail) == ("GO_TO_POINT", code, detail)
    published = [t.data for t in topics_after(observer, 0, "behavior_event") if t.data["uid"] == 1]
    assert published == [event.as_dict()]
    assert len(journal.calls("on_stop")) == 1
    assert 1 not in [uid for _, uid in snapshot(ex).active]
    if action is _interrupt_by_reactivation:
        assert snapshot(ex).active == (("GO_TO_POINT", 2),)
    if action is None:
        assert ex.active_behaviors == ()
        assert ex.capability_references == {ODOMETRY: 1}


def test_events_time_out_with_the_catalog_timeout() -> None:
    """Thesis 4.2.1, behavior process 3 (cont.) -- a goal-based behavior that does not
    finish within its catalog timeout ends with exactly one TIME_OUT, at the timeout."""
    ex, _ = make(SMALL)
    uid = ex.activate_behavior("SLOW").payload["uid"]
    ex.run_for(5.0)
    [event] = events_of(ex, uid)
    assert event.code is EventCode.TIME_OUT
    assert event.time_ns == 500_000_000  # 0.5 s, before GenericBehavior's 1 s success
    assert "0.5 s" in event.detail
    assert ex.active_behaviors == ()


def test_checking_situation_at_different_moments() -> None:
    """Thesis 4.2.1, behavior process 4 -- "Checking situation": the situation service
    is asked on every activation and answers from the current beliefs, so the same
    request is allowed at one moment and refused (with the behavior's reason) at
    another. An exception in check_situation is an error answer, never a crash."""
    journal = Journal()

    class Vehicle(NullVehicle):
        def take_off(self, altitude: float) -> None:
            self._state = VehicleState((0.0, 0.0, altitude), (0.0, 0.0, 0.0), 0.0, 1.0, True, True)

        def land(self) -> None:
            self._state = VehicleState((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0, 1.0, False, False)

    library = {
        "TAKE_OFF": probe(
            "TAKE_OFF",
            journal,
            finish_after=0.2,
            situation=lambda b: Situation.ok_if(not b.holds("flying(self)"), "already flying"),
            on_start=lambda behavior, _: behavior.vehicle.take_off(1.0),
        ),
        "LAND": probe(
            "LAND",
            journal,
            finish_after=0.2,
            situation=lambda b: Situation.ok_if(b.holds("flying(self)"), "not flying"),
            on_start=lambda behavior, _: behavior.vehicle.land(),
        ),
        "WAIT": probe("WAIT", journal, fail_in=("check_situation",)),
    }
    ex, observer = make(library=library, journal=journal, vehicle=Vehicle())
    assert ex.activate_behavior("LAND").error == "LAND: not flying"
    assert ex.activate_behavior("TAKE_OFF").ok
    ex.run_for(0.5)
    assert ex.activate_behavior("TAKE_OFF").error == "TAKE_OFF: already flying"
    assert ex.activate_behavior("LAND").ok
    ex.run_for(0.5)
    assert ex.activate_behavior("TAKE_OFF").ok
    assert [e[1] for e in journal.calls("check_situation")] == [
        "LAND",
        "TAKE_OFF",
        "TAKE_OFF",
        "LAND",
        "TAKE_OFF",
    ]
    situation_calls = [c for c in observer.calls() if c.service.endswith("/check_situation")]
    assert [c.response["ok"] for c in situation_calls] == [False, True, False, True, True]
    failed = ex.activate_behavior("WAIT")
    assert not failed.ok
    assert failed.error == "WAIT: check_situation failed: RuntimeError: boom in check_situation"
    assert "WAIT" not in ex.active_behaviors


# == Behavior coordinator =================================================================
def test_non_launched_behavior_is_an_error() -> None:
    """Thesis 4.2.1, coordinator 1 -- "Non launched behavior": activating a behavior
    that does not exist returns an error (with a suggestion) and changes nothing;
    inhibiting one that is not running is an error too."""
    journal = Journal()
    ex, observer = make(library={"GO_TO_POINT": probe("GO_TO_POINT", journal)}, journal=journal)
    ex.activate_behavior("GO_TO_POINT", GO_TO)
    assert_rejected_cleanly(
        ex,
        observer,
        lambda: ex.activate_behavior("GO_TO_PIONT", GO_TO),
        error="unknown behavior GO_TO_PIONT (did you mean 'GO_TO_POINT'?)",
    )
    assert_rejected_cleanly(
        ex, observer, lambda: ex.activate_behavior("LOOK_AT_POINT"), error="unknown behavior"
    )
    assert_rejected_cleanly(
        ex, observer, lambda: ex.inhibit_behavior("ROTATE"), error="ROTATE is not active"
    )
    assert_rejected_cleanly(
        ex, observer, lambda: ex.inhibit_behavior("NO_SUCH"), error="NO_SUCH is not active"
    )
    # The thesis' own catalog lists LOOK_AT_POINT without defining it: still not launched.
    thesis, thesis_observer = make(THESIS)
    assert_rejected_cleanly(
        thesis,
        thesis_observer,
        lambda: thesis.activate_behavior("LOOK_AT_POINT"),
        error="unknown behavior LOOK_AT_POINT",
    )
    assert len(journal.calls("check_situation")) == 1  # only the good activation asked


def test_behavior_consistency_stops_the_active_one_before_starting() -> None:
    """Thesis 4.2.1, coordinator 2 -- "Behavior consistency": an inconsistent active
    behavior is stopped (INTERRUPTED) before the new one starts; the new one is not
    rejected. Behaviors it is consistent with keep running."""
    journal = Journal()
    library = {
        "ROTATE": probe("ROTATE", journal),
        "GO_TO_POINT": probe("GO_TO_POINT", journal),
        "PAY_ATTENTION": probe("PAY_ATTENTION", journal),
    }
    ex, observer = make(library=library, journal=journal)
    rotate = ex.activate_behavior("ROTATE", {"angle": 45}).payload["uid"]
    attention = ex.activate_behavior("PAY_ATTENTION").payload["uid"]
    ex.step()
    result = ex.activate_behavior("GO_TO_POINT", GO_TO)
    assert result.ok and result.payload["preempted"] == ["ROTATE"]
    [event] = events_of(ex, rotate)
    assert (event.name, event.code) == ("ROTATE", EventCode.INTERRUPTED)
    hooks = [(e[0], e[1]) for e in journal.entries if e[0] in ("on_start", "on_stop")]
    assert hooks[-2:] == [("on_stop", "ROTATE"), ("on_start", "GO_TO_POINT")]
    assert ex.active_behaviors == ("GO_TO_POINT", "PAY_ATTENTION")
    assert events_of(ex, attention) == []
    # The consistency service named the victim before anything was stopped.
    [consistency] = observer.calls("check_consistency")[-1:]
    assert consistency.request == {
        "behavior": "GO_TO_POINT",
        "active_behaviors": ["ROTATE", "PAY_ATTENTION"],
    }
    assert consistency.response == {"ok": False, "error": "", "inconsistent": ["ROTATE"]}


def test_recurrent_and_consistent_behaviors_run_together() -> None:
    """Thesis 4.2.1, coordinator 3 -- "Recurrent behaviors": behaviors that are not
    inconsistent are all activated without errors and run side by side; the recurrent
    one runs until inhibited, past every timeout, and never times out."""
    ex, _ = make()
    names = ["PAY_ATTENTION", "PAY_ATTENTION_TO_VISUAL_MARKERS", "WAIT", "GO_TO_POINT"]
    for name in names:
        result = ex.activate_behavior(name, GO_TO if name == "GO_TO_POINT" else {})
        assert result.ok and result.payload["preempted"] == []
    assert set(ex.active_behaviors) == set(names)
    assert ex.capability_references == {ODOMETRY: 1, SETPOINT: 1, PATH: 1, MARKERS: 2}
    ex.run_for(30.0)  # past GO_TO_POINT's 1 s success and WAIT's
    assert ex.active_behaviors == ("PAY_ATTENTION", "PAY_ATTENTION_TO_VISUAL_MARKERS")
    assert {e.name: e.code for e in ex.events} == {
        "GO_TO_POINT": EventCode.GOAL_ACHIEVED,
        "WAIT": EventCode.GOAL_ACHIEVED,
    }
    # A recurrent behavior that the catalog gives a timeout still never times out.
    small, _ = make(SMALL)
    watch = small.activate_behavior("WATCH").payload["uid"]
    small.run_for(10.0)
    assert small.active_behaviors == ("WATCH",) and small.events == []
    assert small.inhibit_behavior("WATCH").ok
    assert [(e.uid, e.code) for e in small.events] == [(watch, EventCode.INTERRUPTED)]


def test_memory_management_of_the_active_set() -> None:
    """Thesis 4.2.1, coordinator 4 -- "Memory management": behaviors are added to the
    coordinator's memory when activated and removed when they stop in any way (end by
    themselves, preempted, inhibited), and `list_of_active_behaviors` follows; an ended
    behavior can be activated again (a new activation, a new uid)."""
    ex, observer = make()

    def published() -> list[str]:
        return observer.topics("list_of_active_behaviors")[-1]["behaviors"]

    ex.activate_behavior("PAY_ATTENTION")
    assert ex.active_behaviors == ("PAY_ATTENTION",) == tuple(published())
    ex.activate_behavior("GO_TO_POINT", GO_TO)
    assert ex.active_behaviors == ("GO_TO_POINT", "PAY_ATTENTION") == tuple(published())
    ex.activate_behavior("ROTATE", {"angle": 10})
    assert ex.active_behaviors == ("ROTATE", "PAY_ATTENTION") == tuple(published())
    assert ex.run_until(lambda: "ROTATE" not in ex.active_behaviors, timeout_s=5)
    assert ex.active_behaviors == ("PAY_ATTENTION",) == tuple(published())
    ex.inhibit_behavior("PAY_ATTENTION")
    assert ex.active_behaviors == () == tuple(published())
    again = ex.activate_behavior("ROTATE", {"angle": 10})
    assert again.ok and again.payload["uid"] == 4
    assert ex.coordinator.active["ROTATE"].uid == 4
    assert ex.active_behaviors == ("ROTATE",) == tuple(published())
    assert [(e.name, e.uid, e.code.value) for e in ex.events] == [
        ("GO_TO_POINT", 2, "INTERRUPTED"),
        ("ROTATE", 3, "GOAL_ACHIEVED"),
        ("PAY_ATTENTION", 1, "INTERRUPTED"),
    ]


# == Behavior specialist ==================================================================
@pytest.mark.parametrize("path", [DEFAULT_CATALOG, THESIS_CATALOG], ids=["default", "thesis"])
def test_check_consistency_for_every_pair(path: Path) -> None:
    """Thesis 4.2.1, specialist 1 -- "Check consistency": for every pair of catalog
    behaviors the consistency service names the active one inconsistent exactly when
    it is a member of one of the new one's incompatible lists (or is the new one); for
    every pair of capabilities the capability check fails exactly when either lists
    the other as incompatible."""
    raw = file_entries(path)
    catalog = load_catalog(path)
    ex, _ = make(catalog)
    members = {x["list"]: set(x["behaviors"]) for x in raw.get("behavior_lists", [])}
    names = [b["behavior"] for b in raw["behavior_descriptors"]]
    for new in raw["behavior_descriptors"]:
        victims = set().union(*(members.get(x, set()) for x in new.get("incompatible_lists", [])))
        for other in names:
            answer = ex.specialist.check_consistency("test", new["behavior"], [other])
            expect = other == new["behavior"] or other in victims
            assert answer.ok is not expect, (new["behavior"], other)
            assert answer.payload["inconsistent"] == ([other] if expect else [])
    conflicts = {
        c["capability"]: set(c.get("incompatible_capabilities", []))
        for c in raw["capability_descriptors"]
    }
    for a in conflicts:
        for b in conflicts:
            if a == b:
                continue
            answer = ex.specialist.check_capabilities_consistency("test", (a,), (b,))
            assert answer.ok is not (b in conflicts[a] or a in conflicts[b]), (a, b)
    assert not ex.specialist.check_capabilities_consistency("test", (SETPOINT, SERVOING), ()).ok


@pytest.mark.parametrize("path", [DEFAULT_CATALOG, THESIS_CATALOG], ids=["default", "thesis"])
def test_catalog_interpretation_counts(path: Path) -> None:
    """Thesis 4.2.1, specialist 2 -- "Catalog interpretation": the catalog file loads
    and the system has as many behaviors and capabilities as the file contains (one
    behavior process per behavior descriptor)."""
    raw = file_entries(path)
    catalog = load_catalog(path)
    ex, _ = make(catalog)
    behavior_names = [b["behavior"] for b in raw["behavior_descriptors"]]
    capability_names = [c["capability"] for c in raw["capability_descriptors"]]
    assert list(catalog.behaviors) == behavior_names
    assert list(catalog.capabilities) == capability_names
    assert list(ex.behaviors) == behavior_names
    assert all(isinstance(b, GenericBehavior) for b in ex.behaviors.values())
    assert [b.behavior_name for b in ex.behaviors.values()] == behavior_names
    assert list(catalog.lists) == [x["list"] for x in raw.get("behavior_lists", [])]
    expected = {"default": (13, 6), "thesis": (12, 6)}[
        "default" if path == DEFAULT_CATALOG else "thesis"
    ]
    assert (len(ex.behaviors), len(catalog.capabilities)) == expected


@pytest.mark.parametrize("path", [DEFAULT_CATALOG, THESIS_CATALOG], ids=["default", "thesis"])
def test_behaviors_and_capabilities_are_retrieved(path: Path) -> None:
    """Thesis 4.2.1, specialist 3 -- "Behaviors and capabilities are retrieved": every
    concept loaded is sent back correctly: each behavior's capabilities (in file
    order), its default values (timeout, recurrent), its argument format."""
    raw = file_entries(path)
    ex, observer = make(load_catalog(path))
    for entry in raw["behavior_descriptors"]:
        name = entry["behavior"]
        resources = ex.specialist.behavior_resources("test", name)
        assert resources.ok and resources.payload["capabilities"] == entry.get("capabilities", [])
        defaults = ex.specialist.default_values("test", name)
        recurrent = entry.get("recurrent") in (True, "yes")
        assert defaults.payload["recurrent"] is recurrent
        assert defaults.payload["timeout"] == entry.get("timeout", None if recurrent else 15)
        for argument in entry.get("arguments", []):
            allowed = argument["allowed_values"]
            value: Any
            if allowed == "TEXT":
                value = "hello"
            elif isinstance(allowed[0], str):
                value = allowed[-1].lower()  # symbols match case-insensitively
            else:
                value = [allowed[1]] * argument.get("dimensions", 1)
                value = value[0] if len(value) == 1 else value
            form = ex.specialist.check_behavior_format("test", name, {argument["argument"]: value})
            assert form.ok, form.error
            got = form.payload["arguments"][argument["argument"]]
            assert got == (
                allowed[-1] if allowed != "TEXT" and isinstance(allowed[0], str) else value
            )
    unknown = ex.specialist.behavior_resources("test", "NO_SUCH")
    assert not unknown.ok and "unknown behavior NO_SUCH" in unknown.error
    assert observer.calls("behavior_resources")[-1].response["ok"] is False


def test_default_capabilities_activated_at_initiation_and_never_released() -> None:
    """Thesis 4.2.1, specialist 4 -- "Default capabilities": capabilities marked
    active_by_default are activated at initiation (before any behavior) and never drop
    to zero, whatever behaviors come and go, even one that needs them itself."""
    ex, observer = make()
    [initiate] = observer.calls("initiate_resources")
    assert initiate.request == {"capabilities": [ODOMETRY]} and initiate.response["ok"]
    assert initiate.parent_seq == observer.calls("initiate_behaviors")[0].seq
    assert ex.capability_references == {ODOMETRY: 1}
    assert ex.running_processes == ("droneOdometryStateEstimator",)
    args = {"GO_TO_POINT": GO_TO, "ROTATE": {"angle": 5}}
    for name in DEFAULT.behaviors:
        assert ex.activate_behavior(name, args.get(name, {})).ok
        ex.run_for(0.3)
        assert ex.capability_references[ODOMETRY] == 1
    for name in ex.active_behaviors:
        ex.inhibit_behavior(name)
    ex.run_for(3.0)
    assert ex.capability_references == {ODOMETRY: 1}
    assert ex.running_processes == ("droneOdometryStateEstimator",)
    assert ("stopped", "droneOdometryStateEstimator") not in process_changes(observer)
    # A behavior that also needs a default capability adds a reference and gives it back.
    small, small_observer = make(SMALL)
    assert small.capability_references == {"CAMERA": 1}
    small.activate_behavior("WATCH")
    assert small.capability_references == {"CAMERA": 2, "MAPPING": 1}
    small.inhibit_behavior("WATCH")
    assert small.capability_references == {"CAMERA": 1}
    assert small.running_processes == ("camera_driver",)
    assert ("stopped", "camera_driver") not in process_changes(small_observer)


# == Resource manager =====================================================================
@pytest.mark.parametrize("catalog", [DEFAULT, THESIS], ids=["default", "thesis"])
def test_capabilities_are_retrieved_for_each_behavior(catalog: Catalog) -> None:
    """Thesis 4.2.1, resource manager 1 -- "Capabilities are retrieved": activating a
    behavior references exactly the capabilities the catalog associates with it (plus
    the defaults), each once; a capability shared by two active behaviors counts two."""
    defaults = {c: 1 for c in catalog.default_capabilities}
    for name, descriptor in catalog.behaviors.items():
        ex, _ = make(catalog)
        args = {"GO_TO_POINT": GO_TO}.get(name, {})
        assert ex.activate_behavior(name, args).ok
        expected = dict(defaults)
        for capability in descriptor.capabilities:
            expected[capability] = expected.get(capability, 0) + 1
        assert ex.capability_references == expected, name
        holders = {c: h for c, h in ex.resources.holders.items() if name in h}
        assert sorted(holders) == sorted(descriptor.capabilities)
    ex, observer = make(catalog)
    ex.activate_behavior("GO_TO_POINT", GO_TO)
    ex.activate_behavior("PAY_ATTENTION")
    if "PAY_ATTENTION_TO_VISUAL_MARKERS" in catalog.behaviors:
        ex.activate_behavior("PAY_ATTENTION_TO_VISUAL_MARKERS")
        assert ex.capability_references[MARKERS] == 2
        assert process_changes(observer).count(("started", "droneArucoEyeROSModule")) == 1


def test_processes_activated_in_catalog_order_and_deactivated_in_reverse() -> None:
    """Thesis 4.2.1, resource manager 2 -- "Processes are activated and deactivated":
    a behavior's processes start in catalog order (its capability order, then each
    capability's process order) and stop in the reverse order; a process shared by two
    capabilities starts once and stops only when neither is referenced; a capability
    handed from a preempted behavior to its successor keeps its processes running."""
    ex, observer = make()
    ex.activate_behavior("GO_TO_POINT", GO_TO)
    starts = [
        ("started", "droneTrajectoryController"),
        ("started", "droneTrajectoryPlanner"),
        ("started", "droneYawPlanner"),
    ]
    assert process_changes(observer) == [("started", "droneOdometryStateEstimator"), *starts]
    mark = len(observer.records)
    ex.inhibit_behavior("GO_TO_POINT")
    assert process_changes(observer, mark) == [("stopped", p) for _, p in reversed(starts)]
    # Hand-over: ROTATE preempts GO_TO_POINT and keeps the trajectory controller.
    ex.activate_behavior("GO_TO_POINT", GO_TO)
    mark = len(observer.records)
    ex.activate_behavior("ROTATE", {"angle": 90})
    assert process_changes(observer, mark) == [
        ("stopped", "droneYawPlanner"),
        ("stopped", "droneTrajectoryPlanner"),
    ]
    assert ex.capability_references == {ODOMETRY: 1, SETPOINT: 1}
    assert ex.resources.processes["droneTrajectoryController"].running
    # A process shared by a default capability and another one (small catalog).
    small, small_observer = make(SMALL)
    small.activate_behavior("WATCH")
    assert small.running_processes == ("camera_driver", "mapper")
    assert process_changes(small_observer) == [
        ("started", "camera_driver"),
        ("started", "mapper"),
    ]
    small.inhibit_behavior("WATCH")
    assert process_changes(small_observer)[-1] == ("stopped", "mapper")
    assert small.running_processes == ("camera_driver",)


def test_inconsistent_capabilities_are_not_activated() -> None:
    """Thesis 4.2.1, resource manager 3 -- "Consistency is checked": capabilities that
    conflict with referenced ones are not activated, neither through the coordinator
    (the activation is rejected, naming the conflict) nor when the resource manager's
    activate_resources service is called directly (Algorithm 3.7)."""
    ex, observer = make(SMALL)
    ex.activate_behavior("HOLD")
    assert_rejected_cleanly(
        ex,
        observer,
        lambda: ex.activate_behavior("TRACK"),
        error="capability VISUAL_SERVOING conflicts with active capability SETPOINT_CONTROL",
    )
    before = snapshot(ex)
    direct = ex.resources.activate_resources("TRACK")
    assert not direct.ok and "VISUAL_SERVOING" in direct.error
    assert snapshot(ex) == before
    assert "tracker" not in ex.resources.processes
    [check] = observer.calls("check_capabilities_consistency")[-1:]
    assert check.request == {
        "capabilities": [SERVOING],
        "active_capabilities": ["CAMERA", "SETPOINT_CONTROL"],
    }
    assert not check.response["ok"]


# == Integration (the thesis' table) ======================================================
def test_integration_behaviors_are_activated() -> None:
    """Thesis 4.2.1 integration 1 -- "Behaviors are activated": a behavior requested by
    a high-level process (the mission) is activated correctly, as one observes from
    outside: the activate_behavior call answers ok with its uid, its nested service
    calls follow Algorithm 3.5 in order, and the active lists are published."""
    ex, observer = make()
    mark = len(observer.records)
    result = ex.activate_behavior("GO_TO_POINT", {"relative_coordinates": [0, 0, 0.5]})
    assert result.ok
    calls = [r for r in observer.records[mark:] if isinstance(r, ServiceCallRecord)]
    root = calls[-1]
    assert (root.service, root.caller, root.parent_seq) == ("activate_behavior", "mission", None)
    assert root.request == {
        "behavior": "GO_TO_POINT",
        "arguments": {"relative_coordinates": [0, 0, 0.5]},
    }
    assert root.response == {"ok": True, "error": "", "uid": 1, "preempted": []}
    children = sorted((c for c in calls if c.parent_seq == root.seq), key=lambda c: c.seq)
    assert [c.service for c in children] == [
        "check_behavior_format",
        "behavior_go_to_point/check_situation",
        "check_consistency",
        "default_values",
        "behavior_go_to_point/start",
    ]
    assert all(c.response["ok"] or c.service == "check_consistency" for c in children)
    assert children[3].response == {"ok": True, "error": "", "timeout": 120.0, "recurrent": False}
    assert children[4].request == {
        "uid": 1,
        "arguments": {"RELATIVE_COORDINATES": [0, 0, 0.5]},
    }
    assert observer.topics("list_of_active_behaviors")[-1] == {"behaviors": ["GO_TO_POINT"]}
    assert observer.topics("list_of_active_capabilities")[-1] == {
        "capabilities": [
            {"name": SETPOINT, "references": 1},
            {"name": PATH, "references": 1},
            {"name": ODOMETRY, "references": 1},
        ]
    }
    assert ex.run_until(lambda: bool(ex.events), timeout_s=5)
    assert ex.events[0].code is EventCode.GOAL_ACHIEVED and ex.events[0].uid == 1


def test_integration_behaviors_are_stopped() -> None:
    """Thesis 4.2.1 integration 2 -- "Behaviors are stopped": a behavior inhibited by a
    high-level process is stopped, and the pose or speed does not change afterwards:
    the behavior sends the vehicle no further command once inhibited."""
    commands: list[tuple[str, tuple[float, ...]]] = []

    class Recording(NullVehicle):
        def set_velocity(self, vx: float, vy: float, vz: float) -> None:
            commands.append(("set_velocity", (vx, vy, vz)))

        def hover(self) -> None:
            commands.append(("hover", ()))

    class StartMoving(Behavior):
        name = "START_MOVING"

        def on_start(self, args: Mapping[str, Any]) -> None:
            self.speed = float(args.get("SPEED", 1))

        def on_run(self) -> Finished | None:
            self.vehicle.set_velocity(self.speed, 0.0, 0.0)  # keeps pushing each tick
            return None

        def on_stop(self) -> None:
            self.vehicle.hover()

    ex, _ = make(library={"START_MOVING": StartMoving}, vehicle=Recording())
    ex.activate_behavior("START_MOVING", {"speed": 2, "direction": "forward"})
    ex.run_for(1.0)
    assert commands == [("set_velocity", (2.0, 0.0, 0.0))] * 10
    assert ex.inhibit_behavior("START_MOVING").ok
    assert commands[-1] == ("hover", ())
    count = len(commands)
    ex.run_for(20.0)  # past its 15 s timeout: nothing more, not even a TIME_OUT
    assert len(commands) == count
    assert [(e.name, e.code) for e in ex.events] == [("START_MOVING", EventCode.INTERRUPTED)]
    assert ex.active_behaviors == ()


def test_integration_belief_manager() -> None:
    """Thesis 4.2.1 integration 3 -- "Belief manager integration": every time a behavior
    checks its situation, the answer it gets from the belief manager (fed by the
    vehicle) is treated correctly: a grounded vehicle may take off, a flying one may not,
    a low battery refuses the take-off with the behavior's reason."""

    def take_off_situation(beliefs: Beliefs) -> Situation:
        if beliefs.holds("flying(self)"):
            return Situation(False, "already flying")
        low = beliefs.holds("battery_level(self, LOW)")
        return Situation.ok_if(not low, "battery too low to take off")

    def state(flying: bool, battery: float) -> VehicleState:
        return VehicleState(
            (0.0, 0.0, 1.0 if flying else 0.0), (0.0,) * 3, 0.0, battery, flying, flying
        )

    outcomes = {}
    for label, vehicle_state in {
        "grounded": state(False, 0.9),
        "flying": state(True, 0.9),
        "low_battery": state(False, 0.1),
    }.items():
        journal = Journal()
        library = {"TAKE_OFF": probe("TAKE_OFF", journal, situation=take_off_situation)}
        ex, _ = make(library=library, journal=journal, vehicle=NullVehicle(vehicle_state))
        result = ex.activate_behavior("TAKE_OFF")
        outcomes[label] = (result.ok, result.error, ex.active_behaviors)
        assert len(journal.calls("check_situation")) == 1
        found, position = ex.beliefs.query("position(self, (?X, ?Y, ?Z))")
        assert found and position["Z"] == vehicle_state.position[2]
    assert outcomes == {
        "grounded": (True, "", ("TAKE_OFF",)),
        "flying": (False, "TAKE_OFF: already flying", ()),
        "low_battery": (False, "TAKE_OFF: battery too low to take off", ()),
    }


@pytest.mark.parametrize(
    ("behavior", "arguments", "error"),
    [
        (
            "GO_TO_POINT",
            {"coordinates": [1, 2]},
            "COORDINATES needs 3 numbers in [-100, 100], got 2",
        ),
        ("GO_TO_POINT", {"coordinates": [0, 0, 500]}, "(500 is outside)"),
        ("GO_TO_POINT", {"coordinates": "home"}, "COORDINATES needs 3 numbers"),
        ("GO_TO_POINT", {"coordinates": [True, 1, 2]}, "COORDINATES needs 3 numbers"),
        ("GO_TO_POINT", {"speed": 3}, "unknown argument 'speed'"),
        (
            "GO_TO_POINT",
            {"coordinates": [1, 2, 3], "COORDINATES": [1, 2, 3]},
            "COORDINATES given twice",
        ),
        ("ROTATE", {"angle": "left"}, "ANGLE needs a number in [-360, 360]"),
        ("START_MOVING", {"direction": "SIDEWAYS"}, "DIRECTION needs one of BACKWARD"),
        ("BROADCAST_MESSAGE", {"text": 42}, "TEXT needs text, got 42"),
        ("TAKE_OFF", {"altitude": 1}, "(arguments: none)"),
    ],
)
def test_integration_error_management(behavior: str, arguments: dict[str, Any], error: str) -> None:
    """Thesis 4.2.1 integration 4 -- "Error management": an activation with an error
    argument is answered with the error, the behavior is not activated, its situation
    is not even asked, and nothing else changes -- in particular the active behavior it
    would have preempted keeps running."""
    journal = Journal()
    library = {
        behavior: probe(behavior, journal),
        "FLIP": probe("FLIP", journal),
    }
    ex, observer = make(library=library, journal=journal)
    assert ex.activate_behavior("FLIP", {"direction": "back"}).ok  # a motion behavior
    asked = len(journal.calls("check_situation"))
    assert_rejected_cleanly(
        ex, observer, lambda: ex.activate_behavior(behavior, arguments), error=error
    )
    assert ex.active_behaviors == ("FLIP",)
    assert len(journal.calls("check_situation")) == asked
    assert journal.calls("on_start", behavior) == []


# == docs/design.md#the-repairs-of-the-thesis ==========================================
def test_rejected_preemptor_leaves_its_would_be_victim_running() -> None:
    """A rejected activation changes nothing, even when the new behavior would have
    preempted someone: the capability check is decided before any preemption, so the
    would-be victim keeps running, holds its capabilities and gets no event."""
    journal = Journal()
    library = {"MOVE": probe("MOVE", journal), "HOLD": probe("HOLD", journal)}
    ex, observer = make(SMALL, library=library, journal=journal)
    ex.activate_behavior("HOLD")
    ex.activate_behavior("MOVE")
    ex.step()
    # TRACK's list preempts MOVE, but its VISUAL_SERVOING conflicts with HOLD's control.
    assert SMALL.preempted_by("TRACK") >= {"MOVE"}
    assert_rejected_cleanly(
        ex,
        observer,
        lambda: ex.activate_behavior("TRACK"),
        error="conflicts with active capability SETPOINT_CONTROL (held by HOLD)",
    )
    assert ex.active_behaviors == ("MOVE", "HOLD")
    assert journal.calls("on_stop") == []
    assert ex.running_processes == ("camera_driver", "controller", "planner")
    ex.run_for(0.2)
    assert len(journal.calls("on_run", "MOVE")) == 3  # it kept running


def test_zero_reference_bug_is_fixed() -> None:
    """The thesis checked new capabilities against ones whose count had already fallen
    to zero, so a preempting behavior could not take a capability conflicting with the
    one its victim released. aeroexec checks referenced capabilities only:
    FOLLOW_OBJECT_IMAGE (VISUAL_SERVOING) preempts GO_TO_POINT (which held the
    conflicting SETPOINT_BASED_FLIGHT_CONTROL), and the victim's controller is stopped
    before the new one starts, never running beside it."""
    assert SETPOINT in DEFAULT.conflicts_of(SERVOING)
    assert "GO_TO_POINT" in DEFAULT.preempted_by("FOLLOW_OBJECT_IMAGE")
    ex, observer = make()
    go_to = ex.activate_behavior("GO_TO_POINT", GO_TO).payload["uid"]
    mark = len(observer.records)
    result = ex.activate_behavior("FOLLOW_OBJECT_IMAGE")
    assert result.ok, result.error
    assert result.payload["preempted"] == ["GO_TO_POINT"]
    assert [(e.uid, e.code) for e in ex.events] == [(go_to, EventCode.INTERRUPTED)]
    assert ex.capability_references == {ODOMETRY: 1, SERVOING: 1}
    assert process_changes(observer, mark) == [
        ("stopped", "droneYawPlanner"),
        ("stopped", "droneTrajectoryPlanner"),
        ("stopped", "droneTrajectoryController"),
        ("started", "trackerEye"),
        ("started", "open_tld_translator"),
        ("started", "droneIBVSController"),
    ]
    # And back: GO_TO_POINT takes the controller again from FOLLOW_OBJECT_IMAGE.
    assert ex.activate_behavior("GO_TO_POINT", GO_TO).ok
    assert ex.capability_references == {ODOMETRY: 1, SETPOINT: 1, PATH: 1}


@pytest.mark.parametrize("hook", ["check_situation", "on_start", "on_run", "on_stop"])
def test_exception_in_a_hook_never_escapes(hook: str) -> None:
    """An exception in any author hook never escapes into the core: the activation,
    the steps and the inhibit all return normally, at most one PROCESS_FAILURE event is
    sent, nothing stays referenced, and the next activation works."""
    journal = Journal()
    library = {
        "GO_TO_POINT": probe("GO_TO_POINT", journal, fail_in=(hook,)),
        "ROTATE": probe("ROTATE", journal, finish_after=0.5),
    }
    ex, _ = make(library=library, journal=journal)
    first = ex.activate_behavior("GO_TO_POINT", GO_TO)
    assert first.ok is (hook != "check_situation")
    ex.run_for(0.5)
    ex.inhibit_behavior("GO_TO_POINT")
    failures = [e for e in ex.events if e.code is EventCode.PROCESS_FAILURE]
    assert len(failures) == (0 if hook == "check_situation" else 1)
    assert all(f"boom in {hook}" in e.detail for e in failures)
    assert ex.active_behaviors == ()
    assert ex.capability_references == {ODOMETRY: 1}
    assert ex.running_processes == ("droneOdometryStateEstimator",)
    second = ex.activate_behavior("ROTATE", {"angle": 30})
    assert second.ok
    ex.run_for(1.0)
    assert ex.events[-1].uid == second.payload["uid"]
    assert ex.events[-1].code is EventCode.GOAL_ACHIEVED


def test_malformed_hook_results_never_escape() -> None:
    """A hook that returns the wrong type (check_situation returning a bool, on_run a
    string, Finished with an unknown code) is an author bug like an exception: an error
    answer or a PROCESS_FAILURE event, never an exception into the core."""

    class BadSituation(Behavior):
        name = "WAIT"

        def check_situation(self, beliefs: Beliefs) -> Situation:
            return True  # type: ignore[return-value]

    class BadRun(Behavior):
        name = "ROTATE"

        def on_run(self) -> Finished | None:
            return "done"  # type: ignore[return-value]

    class BadCode(Behavior):
        name = "FLIP"

        def on_run(self) -> Finished | None:
            return Finished("SUCCESS")  # type: ignore[arg-type]

    class StringCode(Behavior):
        name = "BROADCAST_MESSAGE"

        def on_run(self) -> Finished | None:
            return Finished("GOAL_ACHIEVED")  # type: ignore[arg-type]

    library = {c.name: c for c in (BadSituation, BadRun, BadCode, StringCode)}
    ex, observer = make(library=library)
    situation = ex.activate_behavior("WAIT")
    assert not situation.ok and "check_situation returned bool" in situation.error
    assert "WAIT" not in ex.active_behaviors
    rotate = ex.activate_behavior("ROTATE", {"angle": 1}).payload["uid"]
    ex.step()
    [event] = events_of(ex, rotate)
    assert event.code is EventCode.PROCESS_FAILURE and "on_run returned str" in event.detail
    flip = ex.activate_behavior("FLIP").payload["uid"]
    ex.step()
    [event] = events_of(ex, flip)
    assert event.code is EventCode.PROCESS_FAILURE and "SUCCESS" in event.detail
    text = ex.activate_behavior("BROADCAST_MESSAGE").payload["uid"]
    ex.step()
    [event] = events_of(ex, text)
    assert event.code is EventCode.GOAL_ACHIEVED
    codes = [t["code"] for t in observer.topics("behavior_event")]
    assert codes == ["PROCESS_FAILURE", "PROCESS_FAILURE", "GOAL_ACHIEVED"]
    assert ex.active_behaviors == ()
