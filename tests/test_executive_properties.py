"""Property tests of the executive core (docs/design.md#invariants).

Hypothesis drives random command sequences -- activate (catalog behaviors and unknown
names, with valid, invalid and junk arguments), inhibit (active or not), step -- over
the default catalog, the thesis' Appendix A catalog and generated catalogs, with
`NullVehicle` and no behavior library (every behavior is a `GenericBehavior`: goal-based
ones succeed after 1 s, recurrent ones run until inhibited). After every command:

* active behaviors are compatible: whenever X was activated, no behavior X preempts
  stayed active -- so for active A and B with A activated first, A is not in B's
  incompatible lists (the converse may hold: B may sit in A's lists, A came first);
* every capability's reference count is the number of active behaviors needing it
  (+1 for a default capability), and nothing else is referenced;
* no two referenced capabilities conflict;
* a process runs iff a referenced capability needs it;
* each activation (uid) produces at most one end event, active ones none;
* a rejected command changes nothing (state, events, published topics, uid counter).

The expectations are computed from the catalog descriptors by this module's own small
model, not by asking the executive's specialist.
"""

from __future__ import annotations

import math
import string
from collections import Counter
from collections.abc import Iterable, Mapping
from typing import Any

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.stateful import (
    RuleBasedStateMachine,
    initialize,
    invariant,
    rule,
)

from aeroexec.catalog import (
    DEFAULT_CATALOG,
    THESIS_CATALOG,
    ArgumentKind,
    ArgumentSpec,
    BehaviorDescriptor,
    Catalog,
    Severity,
    check_arguments,
    load_catalog,
    parse_catalog,
)
from aeroexec.executive import EventCode, Executive, GenericBehavior, MemoryObserver, TopicRecord
from aeroexec.executive.clock import NS_PER_S
from aeroexec.vehicles.null import NullVehicle

DEFAULT = load_catalog(DEFAULT_CATALOG)
THESIS = load_catalog(THESIS_CATALOG)
GENERIC_DURATION_NS = NS_PER_S  # GenericBehavior.duration = 1.0 s
UNKNOWN_NAMES = ("LOOK_AT_POINT", "take_off", "", "NO_SUCH_BEHAVIOR")

#: Conflicts between behaviors that do not preempt each other, so that activations are
#: often rejected -- also ones that would have preempted someone (TRACK over MOVE while
#: HOLD holds the conflicting control) -- and hand-overs of shared capabilities.
CONFLICTS = parse_catalog(
    """
behavior_descriptors:
  - {behavior: MOVE, timeout: 2, recurrent: no, incompatible_lists: [motion],
     capabilities: [CONTROL, PLANNING]}
  - {behavior: TRACK, timeout: 0.5, recurrent: no, incompatible_lists: [motion],
     capabilities: [SERVOING]}
  - {behavior: HOLD, recurrent: yes, capabilities: [CONTROL]}
  - {behavior: LOOK, recurrent: yes, incompatible_lists: [watchers], capabilities: [CAMERA]}
  - {behavior: SCAN, timeout: 15, recurrent: no, incompatible_lists: [motion, watchers],
     capabilities: [CAMERA, PLANNING]}
behavior_lists:
  - {list: motion, behaviors: [MOVE, TRACK, SCAN]}
  - {list: watchers, behaviors: [LOOK]}
capability_descriptors:
  - {capability: CONTROL, processes: [controller], active_by_default: no,
     incompatible_capabilities: [SERVOING]}
  - {capability: PLANNING, processes: [planner, controller], active_by_default: no}
  - {capability: SERVOING, processes: [tracker], active_by_default: no}
  - {capability: CAMERA, processes: [camera], active_by_default: no,
     required_capabilities: [ODOMETRY]}
  - {capability: ODOMETRY, processes: [odometry], active_by_default: yes}
""",
    "conflicts.yaml",
)

MACHINE_SETTINGS = settings(
    max_examples=60,
    stateful_step_count=30,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)


# -- generated catalogs ---------------------------------------------------------------------
def _flow(items: list[str]) -> str:
    return "[" + ", ".join(items) + "]"


@st.composite
def argument_yaml(draw: st.DrawFn, name: str) -> list[str]:
    kind = draw(st.sampled_from(["range", "vector", "symbols", "text"]))
    lines = [f"      - argument: {name}"]
    if kind in ("range", "vector"):
        low = draw(st.integers(-100, 100))
        high = draw(st.integers(low, 200))
        lines.append(f"        allowed_values: [{low}, {high}]")
        if kind == "vector":
            lines.append(f"        dimensions: {draw(st.integers(2, 3))}")
    elif kind == "symbols":
        symbols = draw(
            st.lists(
                st.sampled_from(["UP", "DOWN", "LEFT", "RIGHT"]),
                min_size=1,
                max_size=3,
                unique=True,
            )
        )
        lines.append(f"        allowed_values: {_flow(symbols)}")
    else:
        lines.append("        allowed_values: TEXT")
    return lines


@st.composite
def catalog_texts(draw: st.DrawFn) -> str:
    """Catalog YAML with random behaviors, lists, capabilities (processes, possibly
    shared; conflicts; defaults; acyclic requirements), recurrent flags in either
    dialect's spelling, short and long timeouts, arguments, and a few dangling names."""
    behaviors = [f"B{i}" for i in range(draw(st.integers(1, 7)))]
    lists = [f"L{i}" for i in range(draw(st.integers(0, 3)))]
    capabilities = [f"C{i}" for i in range(draw(st.integers(0, 6)))]
    processes = [f"p{i}" for i in range(draw(st.integers(1, 6)))]
    out = ["behavior_descriptors:"]
    for name in behaviors:
        out.append(f"  - behavior: {name}")
        recurrent = draw(st.booleans())
        spelling = draw(st.sampled_from(["recurrent", "category"]))
        if spelling == "recurrent":
            out.append(f"    recurrent: {'yes' if recurrent else 'no'}")
        else:
            out.append(f"    category: {'recurrent' if recurrent else 'goal_based'}")
        timeout = draw(st.sampled_from([None, 0.25, 0.5, 1, 2, 15]))
        if timeout is not None:
            out.append(f"    timeout: {timeout}")
        chosen_lists = draw(
            st.lists(st.sampled_from([*lists, "L_UNDEFINED"]), max_size=2, unique=True)
        )
        out.append(f"    incompatible_lists: {_flow(chosen_lists)}")
        if capabilities:
            pool = [*capabilities, "C_UNDEFINED"] if draw(st.integers(0, 3)) == 0 else capabilities
            chosen = draw(st.lists(st.sampled_from(pool), max_size=3, unique=True))
            out.append(f"    capabilities: {_flow(chosen)}")
        arguments = draw(st.lists(st.sampled_from(["A", "Bee", "COORDS"]), max_size=2, unique=True))
        if arguments:
            out.append("    arguments:")
            for argument in arguments:
                out.extend(draw(argument_yaml(argument)))
    if lists:
        out.append("behavior_lists:")
        for name in lists:
            members = draw(
                st.lists(st.sampled_from([*behaviors, "B_UNDEFINED"]), max_size=5, unique=True)
            )
            out.append(f"  - list: {name}")
            out.append(f"    behaviors: {_flow(members)}")
    out.append("capability_descriptors:" + ("" if capabilities else " []"))
    for i, name in enumerate(capabilities):
        out.append(f"  - capability: {name}")
        used = draw(st.lists(st.sampled_from(processes), min_size=1, max_size=3, unique=True))
        out.append(f"    processes: {_flow(used)}")
        out.append(f"    active_by_default: {'yes' if draw(st.integers(0, 4)) == 0 else 'no'}")
        others = [c for c in capabilities if c != name]
        if others:
            conflicts = draw(st.lists(st.sampled_from(others), max_size=2, unique=True))
            out.append(f"    incompatible_capabilities: {_flow(conflicts)}")
        if i and draw(st.booleans()):
            required = draw(st.lists(st.sampled_from(capabilities[:i]), max_size=2, unique=True))
            out.append(f"    required_capabilities: {_flow(required)}")
    return "\n".join(out) + "\n"


def _usable(catalog: Catalog) -> bool:
    if any(d.severity is Severity.ERROR for d in catalog.diagnostics):
        return False
    defaults = _closure(catalog, catalog.default_capabilities)
    if defaults is None:
        return False
    return not any(_conflict(catalog, a, b) for a in defaults for b in defaults if a != b)


generated_catalogs = (
    catalog_texts().map(lambda text: parse_catalog(text, "generated.yaml")).filter(_usable)
)


# -- the model: expectations straight from the descriptors ------------------------------
def _conflict(catalog: Catalog, a: str, b: str) -> bool:
    ca, cb = catalog.capabilities.get(a), catalog.capabilities.get(b)
    return bool(
        (ca is not None and b in ca.incompatible_capabilities)
        or (cb is not None and a in cb.incompatible_capabilities)
    )


def _victims(catalog: Catalog, name: str) -> set[str]:
    """Behaviors `name` preempts: members of its incompatible lists."""
    found: set[str] = set()
    for list_name in catalog.behaviors[name].incompatible_lists:
        if list_name in catalog.lists:
            found.update(catalog.lists[list_name].behaviors)
    return found


def _needs(catalog: Catalog, name: str) -> frozenset[str] | None:
    """Capabilities `name` references (requirements included); None if one is undefined."""
    return _closure(catalog, catalog.behaviors[name].capabilities)


def _defaults(catalog: Catalog) -> frozenset[str]:
    """What initiation holds: the default capabilities and everything they require."""
    return _closure(catalog, catalog.default_capabilities) or frozenset()


def _closure(catalog: Catalog, capabilities: Iterable[str]) -> frozenset[str] | None:
    seen: set[str] = set()
    todo = list(capabilities)
    while todo:
        capability = todo.pop()
        if capability in seen:
            continue
        descriptor = catalog.capabilities.get(capability)
        if descriptor is None:
            return None
        seen.add(capability)
        todo.extend(descriptor.required_capabilities)
    return frozenset(seen)


# -- argument strategies ----------------------------------------------------------------
def _valid_value(spec: ArgumentSpec) -> st.SearchStrategy[Any]:
    if spec.kind is ArgumentKind.TEXT:
        return st.text(max_size=8)
    if spec.kind is ArgumentKind.SYMBOLS:
        return st.sampled_from(spec.symbols).flatmap(lambda s: st.sampled_from([s, s.lower()]))
    assert spec.minimum is not None and spec.maximum is not None
    number = st.one_of(
        st.integers(math.ceil(spec.minimum), math.floor(spec.maximum)),
        st.floats(spec.minimum, spec.maximum),
    )
    if spec.dimensions == 1:
        return number
    return st.lists(number, min_size=spec.dimensions, max_size=spec.dimensions)


_junk = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(10**6), 10**6),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(alphabet=string.ascii_letters, max_size=6),
    st.lists(st.one_of(st.integers(-500, 500), st.floats(), st.text(max_size=2)), max_size=4),
)


@st.composite
def arguments_for(draw: st.DrawFn, descriptor: BehaviorDescriptor | None) -> dict[str, Any]:
    specs = descriptor.arguments if descriptor else ()
    mode = draw(st.sampled_from(["valid", "valid", "invalid", "junk"]))
    args: dict[str, Any] = {}
    if mode == "valid" or mode == "invalid":
        for spec in specs:
            if draw(st.booleans()):
                key = draw(st.sampled_from([spec.name, spec.name.lower()]))
                args[key] = draw(_valid_value(spec))
        if mode == "invalid":
            if specs and draw(st.booleans()):
                spec = draw(st.sampled_from(specs))
                args[spec.name] = draw(_junk)
            else:
                args[draw(st.sampled_from(["speed", "altitude", "X"]))] = draw(_junk)
        return args
    names = [s.name for s in specs] + ["other", "ANGLE"]
    return draw(st.dictionaries(st.sampled_from(names), _junk, max_size=3))


# -- the machine ------------------------------------------------------------------------
def _state(ex: Executive) -> tuple[Any, ...]:
    res = ex.resources
    return (
        tuple((n, ex.coordinator.active[n].uid) for n in ex.active_behaviors),
        tuple(n for n, b in ex.behaviors.items() if b.running),
        tuple(sorted(res.references.items())),
        tuple(sorted((c, tuple(h)) for c, h in res.holders.items())),
        ex.running_processes,
        tuple(sorted((n, p.state.value) for n, p in res.processes.items())),
        tuple(ex.events),
    )


class ExecutiveMachine(RuleBasedStateMachine):
    """Subclasses choose the catalogs by overriding `catalogs`."""

    catalogs: st.SearchStrategy[Catalog] = st.just(DEFAULT)

    def __init__(self) -> None:
        super().__init__()
        self.ex: Executive | None = None
        self.observer = MemoryObserver()
        self.catalog = DEFAULT
        self.observed = True
        self.started_ns: dict[int, int] = {}
        self.last_uid = 0

    # -- helpers -------------------------------------------------------------------------
    @property
    def executive(self) -> Executive:
        assert self.ex is not None
        return self.ex

    def active_uids(self) -> dict[str, int]:
        return {n: b.uid for n, b in self.executive.coordinator.active.items()}

    def topics_since(self, mark: int) -> list[TopicRecord]:
        return [r for r in self.observer.records[mark:] if isinstance(r, TopicRecord)]

    def expected_activation(self, name: str, args: Mapping[str, Any]) -> tuple[bool, list[str]]:
        """(accepted?, victims in catalog order) according to the model."""
        catalog = self.catalog
        descriptor = catalog.behaviors.get(name)
        if descriptor is None or not check_arguments(descriptor, args).ok:
            return False, []
        needs = _needs(catalog, name)
        if needs is None:
            return False, []
        preempted = _victims(catalog, name)
        active = list(self.executive.coordinator.active)
        victims = [b for b in active if b == name or b in preempted]
        keep: set[str] = set(_defaults(catalog))
        for other in active:
            if other not in victims:
                keep |= _needs(catalog, other) or frozenset()
        together = sorted(keep | needs)
        ok = not any(
            _conflict(catalog, a, b) for i, a in enumerate(together) for b in together[i + 1 :]
        )
        return ok, sorted(victims, key=list(catalog.behaviors).index)

    # -- rules ---------------------------------------------------------------------------
    @initialize(data=st.data())
    def build(self, data: st.DataObject) -> None:
        self.catalog = data.draw(self.catalogs, label="catalog")
        # Unobserved, the core takes its fast path: it must keep the same invariants.
        self.observed = data.draw(st.booleans(), label="observed")
        observers = [self.observer] if self.observed else []
        self.ex = Executive(
            self.catalog,
            vehicle=NullVehicle(),
            library={},
            stand_in=GenericBehavior,
            observers=observers,
        )
        assert self.ex.initiation.ok, self.ex.initiation.error

    @rule(data=st.data())
    def activate(self, data: st.DataObject) -> None:
        ex = self.executive
        known = st.sampled_from(list(self.catalog.behaviors))
        names = st.one_of(known, known, known, known, known, st.sampled_from(UNKNOWN_NAMES))
        name = data.draw(names, label="behavior")
        args = data.draw(arguments_for(self.catalog.behaviors.get(name)), label="arguments")
        expected_ok, expected_victims = self.expected_activation(name, args)
        before = _state(ex)
        victim_uids = {v: self.active_uids()[v] for v in expected_victims}
        events_before = len(ex.events)
        mark = len(self.observer.records)
        result = ex.activate_behavior(name, args)
        assert result.ok is expected_ok, (name, args, result)
        if not result.ok:
            assert result.error
            assert _state(ex) == before, "a rejected activation changed the executive"
            assert self.topics_since(mark) == [], "a rejected activation published"
            return
        uid = result.payload["uid"]
        assert uid == self.last_uid + 1, "uids are consecutive over accepted activations"
        self.last_uid = uid
        self.started_ns[uid] = ex.clock.now_ns()
        assert result.payload["preempted"] == expected_victims
        new_events = ex.events[events_before:]
        assert [(e.name, e.uid, e.code) for e in new_events] == [
            (v, victim_uids[v], EventCode.INTERRUPTED) for v in expected_victims
        ]
        assert self.active_uids().get(name) == uid

    @rule(data=st.data())
    def inhibit(self, data: st.DataObject) -> None:
        ex = self.executive
        active = sorted(self.active_uids())
        name = data.draw(
            st.sampled_from(active)
            if active and data.draw(st.booleans())
            else st.sampled_from([*self.catalog.behaviors, *UNKNOWN_NAMES]),
            label="inhibit",
        )
        uid = self.active_uids().get(name)
        before = _state(ex)
        events_before = len(ex.events)
        mark = len(self.observer.records)
        result = ex.inhibit_behavior(name)
        if uid is None:
            assert not result.ok
            assert _state(ex) == before
            assert self.topics_since(mark) == []
            return
        assert result.ok
        assert [(e.name, e.uid, e.code) for e in ex.events[events_before:]] == [
            (name, uid, EventCode.INTERRUPTED)
        ]
        assert name not in self.active_uids()

    @rule(ticks=st.integers(1, 12))
    def step(self, ticks: int) -> None:
        ex = self.executive
        for _ in range(ticks):
            events_before = len(ex.events)
            ex.step()
            now = ex.clock.now_ns()
            for event in ex.events[events_before:]:
                descriptor = self.catalog.behaviors[event.name]
                assert not descriptor.recurrent, "a recurrent behavior ended by itself"
                assert event.time_ns == now
                ran = now - self.started_ns[event.uid]
                assert ran == self._expected_run_ns(descriptor), (event, ran)
                assert event.code is (
                    EventCode.GOAL_ACHIEVED
                    if descriptor.timeout is None or descriptor.timeout >= 1.0
                    else EventCode.TIME_OUT
                )
            for name, uid in self.active_uids().items():
                descriptor = self.catalog.behaviors[name]
                if not descriptor.recurrent:
                    assert now - self.started_ns[uid] < self._expected_run_ns(descriptor)

    def _expected_run_ns(self, descriptor: BehaviorDescriptor) -> int:
        """GenericBehavior succeeds after 1 s unless its timeout comes first (checked at
        the first tick at or after the deadline)."""
        tick = self.executive.clock.tick_ns
        if descriptor.timeout is None or descriptor.timeout >= 1.0:
            return GENERIC_DURATION_NS
        deadline = round(descriptor.timeout * NS_PER_S)
        return -(-deadline // tick) * tick

    # -- invariants ----------------------------------------------------------------------
    @invariant()
    def active_behaviors_are_compatible(self) -> None:
        if self.ex is None:
            return
        uids = self.active_uids()
        for earlier, a in uids.items():
            for later, b in uids.items():
                if a < b:
                    assert earlier not in _victims(self.catalog, later), (earlier, later)
        assert set(self.executive.active_behaviors) == set(uids)
        running = {n for n, b in self.executive.behaviors.items() if b.running}
        assert running == set(uids)

    @invariant()
    def references_count_active_needs(self) -> None:
        if self.ex is None:
            return
        expected: Counter[str] = Counter(_defaults(self.catalog))
        for name in self.active_uids():
            needs = _needs(self.catalog, name)
            assert needs is not None
            expected.update(needs)
        assert self.executive.capability_references == dict(expected)
        holders = self.executive.resources.holders
        assert {c: len(h) for c, h in holders.items()} == dict(expected)

    @invariant()
    def referenced_capabilities_do_not_conflict(self) -> None:
        if self.ex is None:
            return
        referenced = sorted(self.executive.capability_references)
        for i, a in enumerate(referenced):
            for b in referenced[i + 1 :]:
                assert not _conflict(self.catalog, a, b), (a, b)

    @invariant()
    def processes_run_iff_needed(self) -> None:
        if self.ex is None:
            return
        needed = {
            p
            for c in self.executive.capability_references
            for p in self.catalog.capabilities[c].processes
        }
        running = self.executive.running_processes
        assert len(running) == len(set(running))
        assert set(running) == needed
        for name, process in self.executive.resources.processes.items():
            assert process.running is (name in needed), name

    @invariant()
    def one_end_event_per_activation(self) -> None:
        if self.ex is None:
            return
        counts = Counter(e.uid for e in self.executive.events)
        assert all(n == 1 for n in counts.values()), counts
        assert not set(counts) & set(self.active_uids().values())
        assert set(counts) | set(self.active_uids().values()) == set(range(1, self.last_uid + 1))

    @invariant()
    def published_lists_match(self) -> None:
        if self.ex is None or not self.observed:
            return
        behaviors = self.observer.topics("list_of_active_behaviors")
        if behaviors:
            assert tuple(behaviors[-1]["behaviors"]) == self.executive.active_behaviors
        capabilities = self.observer.topics("list_of_active_capabilities")
        assert capabilities, "initiation publishes the capabilities"
        published = {c["name"]: c["references"] for c in capabilities[-1]["capabilities"]}
        assert published == self.executive.capability_references


class DefaultCatalogMachine(ExecutiveMachine):
    catalogs = st.just(DEFAULT)


class ThesisCatalogMachine(ExecutiveMachine):
    catalogs = st.just(THESIS)


class ConflictCatalogMachine(ExecutiveMachine):
    catalogs = st.just(CONFLICTS)


class GeneratedCatalogMachine(ExecutiveMachine):
    catalogs = generated_catalogs


TestDefaultCatalog = DefaultCatalogMachine.TestCase
TestDefaultCatalog.settings = MACHINE_SETTINGS
TestThesisCatalog = ThesisCatalogMachine.TestCase
TestThesisCatalog.settings = MACHINE_SETTINGS
TestConflictCatalog = ConflictCatalogMachine.TestCase
TestConflictCatalog.settings = MACHINE_SETTINGS
TestGeneratedCatalogs = GeneratedCatalogMachine.TestCase
TestGeneratedCatalogs.settings = settings(MACHINE_SETTINGS, max_examples=100)


def test_generated_catalogs_are_varied() -> None:
    """The catalog strategy reaches what the machine is meant to exercise (a guard
    against a strategy that silently degenerates to trivial catalogs)."""
    seen: set[str] = set()

    @settings(
        max_examples=100,
        deadline=None,
        suppress_health_check=[HealthCheck.filter_too_much, HealthCheck.too_slow],
    )
    @given(generated_catalogs)
    def look(catalog: Catalog) -> None:
        if catalog.default_capabilities:
            seen.add("default capability")
        if any(c.incompatible_capabilities for c in catalog.capabilities.values()):
            seen.add("conflict")
        if any(c.required_capabilities for c in catalog.capabilities.values()):
            seen.add("requirement")
        if any(b.recurrent for b in catalog.behaviors.values()):
            seen.add("recurrent")
        if any(b.timeout is not None and b.timeout < 1 for b in catalog.behaviors.values()):
            seen.add("short timeout")
        if any(_victims(catalog, b) for b in catalog.behaviors):
            seen.add("preemption")
        if any(_needs(catalog, b) is None for b in catalog.behaviors):
            seen.add("undefined capability")
        processes = [p for c in catalog.capabilities.values() for p in c.processes]
        if len(processes) != len(set(processes)):
            seen.add("shared process")

    look()
    assert seen == {
        "default capability",
        "conflict",
        "requirement",
        "recurrent",
        "short timeout",
        "preemption",
        "undefined capability",
        "shared process",
    }
