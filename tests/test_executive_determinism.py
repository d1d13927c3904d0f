"""Determinism of the executive core (docs/design.md#determinism).

The same commands over the same catalog (and world and seed) give the same observed
message stream, record for record: content, field order, log time, seq and parent_seq.
Checked within one process (two executives) and across processes with different
`PYTHONHASHSEED`s, which is what exposes iteration over sets or hash-ordered data
reaching the output. The call tree rebuilt from seq/parent_seq is well formed.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from aeroexec.catalog import DEFAULT_CATALOG, load_catalog
from aeroexec.executive import (
    EventCode,
    Executive,
    GenericBehavior,
    MemoryObserver,
    ServiceCallRecord,
    TopicRecord,
)
from aeroexec.vehicles.base import Vehicle
from aeroexec.vehicles.null import NullVehicle

DEFAULT = load_catalog(DEFAULT_CATALOG)
HERE = Path(__file__).resolve().parent

Command = tuple[Any, ...]

#: Exercises every path: rejections (unknown, bad argument, capability conflict cannot
#: happen in the default catalog), preemption with hand-over, the zero-reference fix,
#: self-restart, recurrent behaviors, goal-based ones ending by themselves, inhibits of
#: active and inactive behaviors, beliefs.
NULL_COMMANDS: tuple[Command, ...] = (
    ("activate", "PAY_ATTENTION", {}),
    ("activate", "GO_TO_POINT", {"coordinates": [1, 2, 3]}),
    ("step", 3),
    ("activate", "ROTATE", {"angle": 90}),
    ("activate", "NO_SUCH", {}),
    ("activate", "GO_TO_POINT", {"coordinates": [1, 2]}),
    ("step", 4),
    ("activate", "FOLLOW_OBJECT_IMAGE", {}),
    ("activate", "GO_TO_POINT", {"relative_coordinates": [0, 0, 0.5]}),
    ("activate", "GO_TO_POINT", {"relative_coordinates": [0, 0, 0.5]}),
    ("activate", "WAIT", {"duration": 5}),
    ("activate", "PAY_ATTENTION_TO_VISUAL_MARKERS", {}),
    ("step", 15),
    ("inhibit", "PAY_ATTENTION"),
    ("inhibit", "PAY_ATTENTION"),
    ("activate", "BROADCAST_MESSAGE", {"text": "hello"}),
    ("activate", "START_MOVING", {"speed": 2, "direction": "up"}),
    ("step", 5),
    ("inhibit", "START_MOVING"),
    ("step", 20),
)

#: The thesis' Appendix C mission, driven at the core level (execute = activate, then
#: step until that activation's event), for the simulated vehicle and real behaviors.
SIM_COMMANDS: tuple[Command, ...] = (
    ("execute", "TAKE_OFF", {}),
    ("activate", "PAY_ATTENTION_TO_VISUAL_MARKERS", {}),
    ("execute", "GO_TO_POINT", {"relative_coordinates": [0, 0, 0.5]}),
    ("execute", "GO_TO_POINT", {"coordinates": [3, 5.5, 1.3]}),
    ("execute", "ROTATE", {"angle": -90}),
    ("execute", "GO_TO_POINT", {"coordinates": [0, 0, 1.5]}),
    ("inhibit", "PAY_ATTENTION_TO_VISUAL_MARKERS"),
    ("execute", "LAND", {}),
)


def drive(ex: Executive, commands: Sequence[Command]) -> list[str]:
    """Run the commands; returns the outcome of each (for the test's own asserts)."""
    outcomes: list[str] = []
    for command in commands:
        kind = command[0]
        if kind == "activate":
            result = ex.activate_behavior(command[1], command[2])
            outcomes.append("ok" if result.ok else "refused")
        elif kind == "inhibit":
            outcomes.append("ok" if ex.inhibit_behavior(command[1]).ok else "refused")
        elif kind == "step":
            for _ in range(command[1]):
                ex.step()
            outcomes.append("stepped")
        elif kind == "execute":
            result = ex.activate_behavior(command[1], command[2])
            assert result.ok, result.error
            uid: int = result.payload["uid"]
            assert ex.run_until(lambda uid=uid: any(e.uid == uid for e in ex.events), 300)
            outcomes.append(next(e.code.value for e in ex.events if e.uid == uid))
        else:  # pragma: no cover - a typo in a command table
            raise AssertionError(kind)
    return outcomes


def canonical(record: ServiceCallRecord | TopicRecord) -> str:
    """The record as text, field order and dict order included (no sort_keys)."""
    if isinstance(record, ServiceCallRecord):
        fields: dict[str, Any] = {
            "kind": "call",
            **record.as_dict(),
            "log_time_ns": record.log_time_ns,
        }
    else:
        fields = {
            "kind": "topic",
            "topic": record.topic,
            "data": record.data,
            "log_time_ns": record.log_time_ns,
        }
    return json.dumps(fields, allow_nan=True)


def null_session(commands: Sequence[Command] = NULL_COMMANDS) -> tuple[list[str], list[str]]:
    observer = MemoryObserver()
    ex = Executive(
        DEFAULT, vehicle=NullVehicle(), library={}, stand_in=GenericBehavior, observers=[observer]
    )
    outcomes = drive(ex, commands)
    return [canonical(r) for r in observer.records], outcomes


def sim_session(seed: int = 7) -> tuple[list[str], list[str]]:
    from aeroexec.behaviors import STANDARD_LIBRARY
    from aeroexec.vehicles.sim import SimVehicle

    observer = MemoryObserver()
    vehicle: Vehicle = SimVehicle(seed=seed)
    ex = Executive(DEFAULT, vehicle=vehicle, library=STANDARD_LIBRARY, observers=[observer])
    outcomes = drive(ex, SIM_COMMANDS)
    return [canonical(r) for r in observer.records], outcomes


SESSIONS: dict[str, Callable[[], tuple[list[str], list[str]]]] = {
    "null": null_session,
    "sim": sim_session,
}


def in_subprocess(session: str, hash_seed: str) -> list[str]:
    """The session's canonical records, computed by a fresh interpreter."""
    code = (
        "import sys, json; sys.path.insert(0, sys.argv[1]); "
        "import test_executive_determinism as t; "
        "print(json.dumps(t.SESSIONS[sys.argv[2]]()[0]))"
    )
    env = {**os.environ, "PYTHONHASHSEED": hash_seed}
    done = subprocess.run(
        [sys.executable, "-c", code, str(HERE), session],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def call_records(lines: list[str]) -> list[dict[str, Any]]:
    return [r for r in map(json.loads, lines) if r["kind"] == "call"]


def assert_same_stream(a: list[str], b: list[str]) -> None:
    assert len(a) == len(b)
    for i, (x, y) in enumerate(zip(a, b, strict=True)):
        assert x == y, f"records differ first at #{i}:\n{x}\n{y}"


def assert_call_tree_well_formed(lines: list[str]) -> None:
    """seq numbers are 0..n-1 in start order; every parent_seq names a call that started
    earlier and completed later (calls are seen on completion, so children come first)
    at a log time no earlier; calls nest (every call started between a parent and its
    child is a descendant of that parent); calls from the mission are roots."""
    calls = call_records(lines)
    position = {c["seq"]: i for i, c in enumerate(calls)}
    by_seq = {c["seq"]: c for c in calls}
    assert sorted(by_seq) == list(range(len(calls))), "seq must count every call once"
    for call in calls:
        parent = call["parent_seq"]
        if call["caller"] == "mission":
            assert parent is None, call
        if parent is None:
            continue
        assert parent in by_seq and parent < call["seq"], call
        assert position[parent] > position[call["seq"]], "a parent completes after its child"
        assert by_seq[parent]["log_time_ns"] >= call["log_time_ns"]

    def ancestors(seq: int) -> set[int]:
        found: set[int] = set()
        parent = by_seq[seq]["parent_seq"]
        while parent is not None:
            found.add(parent)
            parent = by_seq[parent]["parent_seq"]
        return found

    for call in calls:
        parent = call["parent_seq"]
        if parent is None:
            continue
        for between in range(parent + 1, call["seq"]):
            assert parent in ancestors(between), (parent, between, call["seq"])
    roots = {c["service"] for c in calls if c["parent_seq"] is None}
    assert roots <= {
        "initiate_behaviors",
        "activate_behavior",
        "inhibit_behavior",
        "cancel_resources",
    }
    assert {"activate_behavior", "initiate_behaviors"} <= roots


# -- NullVehicle, no library: the core alone --------------------------------------------
def test_same_commands_same_stream() -> None:
    """Two executives given the same commands observe identical streams, including log
    times and seq/parent_seq; and the stream has the expected shape (so the comparison
    is not between two empty lists)."""
    first, outcomes = null_session()
    second, again = null_session()
    assert outcomes == again
    assert_same_stream(first, second)
    assert outcomes.count("refused") == 3  # NO_SUCH, bad GO_TO_POINT, second inhibit
    records = [json.loads(line) for line in first]
    topics = {r["topic"] for r in records if r["kind"] == "topic"}
    assert {"behavior_event", "process_state", "list_of_active_behaviors", "beliefs"} <= topics
    times = [r["log_time_ns"] for r in records]
    assert times == sorted(times) and times[-1] == 47 * 100_000_000


def test_different_commands_different_stream() -> None:
    """The comparison is sensitive: one changed argument changes the stream."""
    changed = tuple(
        ("activate", "ROTATE", {"angle": 91}) if c == ("activate", "ROTATE", {"angle": 90}) else c
        for c in NULL_COMMANDS
    )
    assert null_session()[0] != null_session(changed)[0]


def test_call_tree_is_well_formed() -> None:
    """The call tree rebuilt from seq/parent_seq is well formed, and an activation's
    nested calls hang under it in the order of Algorithm 3.5."""
    lines, _ = null_session()
    assert_call_tree_well_formed(lines)
    calls = call_records(lines)
    rotate = next(
        c
        for c in calls
        if c["service"] == "activate_behavior" and c["request"]["behavior"] == "ROTATE"
    )
    children = sorted(
        (c for c in calls if c["parent_seq"] == rotate["seq"]), key=lambda c: c["seq"]
    )
    assert [(c["service"], c["caller"]) for c in children] == [
        ("check_behavior_format", "behavior_coordinator"),
        ("behavior_rotate/check_situation", "behavior_coordinator"),
        ("check_consistency", "behavior_coordinator"),
        ("default_values", "behavior_coordinator"),
        ("cancel_resources", "behavior_go_to_point"),  # the preempted GO_TO_POINT
        ("behavior_rotate/start", "behavior_coordinator"),
    ]
    ends = [c for c in calls if c["service"] == "cancel_resources" and c["parent_seq"] is None]
    assert ends, "a behavior ending by itself during step() releases from a root call"


def test_stream_independent_of_hash_seed() -> None:
    """Fresh interpreters with different PYTHONHASHSEEDs record the same stream as this
    process: no set or hash order reaches the output."""
    here, _ = null_session()
    assert_same_stream(in_subprocess("null", "1"), here)
    assert_same_stream(in_subprocess("null", "4242"), here)


# -- SimVehicle and the standard library ------------------------------------------------
def test_simulated_mission_is_deterministic() -> None:
    """The Appendix C mission with the simulated vehicle and the standard behaviors:
    the same seed gives the same stream (vehicle state, beliefs, events, every call),
    in this process and in another one with a different hash seed."""
    first, outcomes = sim_session()
    assert outcomes == [
        "GOAL_ACHIEVED",
        "ok",
        "GOAL_ACHIEVED",
        "GOAL_ACHIEVED",
        "GOAL_ACHIEVED",
        "GOAL_ACHIEVED",
        "ok",
        "GOAL_ACHIEVED",
    ]
    second, _ = sim_session()
    assert_same_stream(first, second)
    assert_call_tree_well_formed(first)
    records = [json.loads(line) for line in first]
    states = [r for r in records if r["kind"] == "topic" and r["topic"] == "vehicle/state"]
    assert len(states) > 100 and states[-1]["data"]["flying"] is False
    markers = [r for r in records if r["kind"] == "topic" and r["topic"] == "beliefs"]
    assert any("visual_marker" in r["data"]["belief"] for r in markers)
    assert_same_stream(in_subprocess("sim", "99"), first)


def test_event_times_are_clock_times() -> None:
    """Log times come from the executive clock only: every behavior_event's log time is
    the event's own clock time, a whole number of ticks."""
    observer = MemoryObserver()
    ex = Executive(
        DEFAULT, vehicle=NullVehicle(), library={}, stand_in=GenericBehavior, observers=[observer]
    )
    drive(ex, NULL_COMMANDS)
    published = [
        r for r in observer.records if isinstance(r, TopicRecord) and r.topic == "behavior_event"
    ]
    assert [r.data["uid"] for r in published] == [e.uid for e in ex.events]
    assert [r.log_time_ns for r in published] == [e.time_ns for e in ex.events]
    assert all(t % ex.clock.tick_ns == 0 for t in (e.time_ns for e in ex.events))
    assert {e.code for e in ex.events} == {EventCode.GOAL_ACHIEVED, EventCode.INTERRUPTED}


def _state(ex: Executive) -> tuple[Any, ...]:
    return (
        tuple((n, ex.coordinator.active[n].uid) for n in ex.active_behaviors),
        tuple(ex.events),
        tuple(sorted(ex.capability_references.items())),
        tuple(sorted((c, tuple(h)) for c, h in ex.resources.holders.items())),
        ex.running_processes,
        tuple(ex.beliefs.texts()),
        ex.clock.now_ns(),
    )


def test_observing_does_not_change_behavior() -> None:
    """With nobody observing, the core takes its fast path (no request payloads, no
    closures); it must behave exactly as when observed: same results, events, active
    set, references, processes and beliefs after every command -- and the same seq
    numbering, so an observer attached later sees the numbers it would have seen."""
    observed = Executive(
        DEFAULT,
        vehicle=NullVehicle(),
        library={},
        stand_in=GenericBehavior,
        observers=[MemoryObserver()],
    )
    quiet = Executive(DEFAULT, vehicle=NullVehicle(), library={}, stand_in=GenericBehavior)
    for command in NULL_COMMANDS:
        assert drive(observed, [command]) == drive(quiet, [command]), command
        assert _state(observed) == _state(quiet), command
    late = MemoryObserver()
    quiet.bus.attach(late)
    watcher = MemoryObserver()
    observed.bus.attach(watcher)
    for ex in (observed, quiet):
        ex.activate_behavior("GO_TO_POINT", {"coordinates": [0, 0, 1]})
        ex.inhibit_behavior("GO_TO_POINT")
    assert [canonical(r) for r in late.records] == [canonical(r) for r in watcher.records]
    assert late.calls()[0].seq > 100
