"""One generated mission run through `simulate()` and judged.

The judges: the properties (`aeroexec:safety` and the user's `--spec` files), evaluated by
the same online monitor `aeroexec run --spec` uses, and the executive's own invariants
(`Invariants`), checked at every tick: each capability's reference count is the number of
its holders, each holder is active (or the defaults), each active behavior holds its
capabilities, a process runs iff a referenced capability needs it, and every service call
was answered. Recording is off: a fuzzer runs a thousand missions a minute and writes the
recording of the few that break something (`output.py`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

from aeroexec.catalog.loader import load_catalog
from aeroexec.catalog.model import Catalog
from aeroexec.errors import WorldError
from aeroexec.executive.executive import Executive
from aeroexec.executive.messages import ServiceCallRecord, TopicRecord
from aeroexec.executive.resources import DEFAULTS
from aeroexec.fuzz.steps import Ending, Mission, ending_for, mission_text, world_text
from aeroexec.inputs import read_text
from aeroexec.mission.script import compile_mission
from aeroexec.mission.session import (
    DEFAULT_MAX_SIM_TIME_S,
    SessionConfig,
    SessionResult,
    simulate,
)
from aeroexec.plugins.discovery import BehaviorSet, BehaviorSources, discovered, standard_set
from aeroexec.properties.check import VIOLATED
from aeroexec.properties.monitor import PropertyMonitor
from aeroexec.properties.spec import PropertySet, load_properties
from aeroexec.vehicles.world import DEFAULT_WORLD

SAFETY = "aeroexec:safety"
#: The names findings of the executive's own invariants are reported under.
REFERENCE_COUNTS = "invariant:reference_counts"
ANSWERED_CALLS = "invariant:answered_calls"
#: A generated mission is stopped where `aeroexec run` stops it (it has at most a dozen
#: commands, each bounded by its behavior's timeout, or by the API's hour for none).
MAX_SIM_TIME_S = DEFAULT_MAX_SIM_TIME_S
MISSION_NAME = "mission.py"
WORLD_NAME = "world.yaml"


@dataclass(frozen=True, slots=True)
class Violation:
    #: The property's name, or `invariant:...`.
    name: str
    message: str
    #: The property's robustness (None for an invariant).
    robustness: float | None = None


@dataclass(frozen=True)
class Target:
    """What the fuzzer runs missions against (plain data: a worker process or a Ray
    task rebuilds the rest with `Bench.of`)."""

    catalog: str
    specs: tuple[str, ...] = (SAFETY,)
    seed: int = 0
    behaviors: BehaviorSources | None = None
    allow_unimplemented: bool = False
    #: The fault kinds to inject (None: every kind the simulator knows).
    fault_kinds: tuple[str, ...] | None = None


@dataclass
class Bench:
    """A `Target` loaded: catalog, properties, behaviors, the world faults go into."""

    target: Target
    catalog: Catalog
    properties: PropertySet
    behaviors: BehaviorSet
    world: str

    @staticmethod
    def of(target: Target) -> Bench:
        return _bench(target)

    def ending(self, mission: Mission) -> Ending:
        return ending_for(mission, self.catalog)

    def texts(self, mission: Mission, header: tuple[str, ...] = ()) -> tuple[str, str]:
        """The mission script and the world file of `mission`."""
        return (
            mission_text(mission, self.ending(mission), header),
            world_text(self.world, mission),
        )


@lru_cache(maxsize=8)
def _bench(target: Target) -> Bench:
    catalog = load_catalog(target.catalog)
    properties = load_properties(target.specs)
    found = discovered(target.behaviors) if target.behaviors is not None else standard_set()
    world = read_text(DEFAULT_WORLD, "a world file", WorldError)
    return Bench(target, catalog, properties, found, world)


@dataclass
class Judgement:
    violations: tuple[Violation, ...]
    #: The least robustness of each property (what Hypothesis' `target` pushes down).
    robustness: dict[str, float] = field(default_factory=dict)
    result: SessionResult | None = None


class Invariants:
    """The executive's invariants, checked once a tick (on its vehicle state)."""

    def __init__(self) -> None:
        self.executive: Executive | None = None
        self.broken: dict[str, str] = {}

    def session_started(self, executive: Executive) -> None:
        self.executive = executive

    def on_service_call(self, record: ServiceCallRecord) -> None:
        response = record.response
        if ANSWERED_CALLS not in self.broken and not (
            isinstance(response, dict) and isinstance(response.get("ok"), bool)
        ):
            self.broken[ANSWERED_CALLS] = (
                f"{record.service} called by {record.caller} at "
                f"{record.log_time_ns / 1e9:.2f} s got no answer ({response!r})"
            )

    def on_topic(self, record: TopicRecord) -> None:
        executive = self.executive
        if record.topic != "vehicle/state" or executive is None:
            return
        if REFERENCE_COUNTS not in self.broken:
            problem = reference_problem(executive)
            if problem:
                at = record.log_time_ns / 1e9
                self.broken[REFERENCE_COUNTS] = f"at {at:.2f} s: {problem}"


def reference_problem(executive: Executive) -> str:
    """What is wrong with the resource manager's books ('' when nothing is)."""
    manager = executive.resources
    active = set(executive.active_behaviors)
    for capability, count in manager.references.items():
        holders = manager.holders.get(capability, [])
        if count != len(holders):
            return f"{capability} has reference count {count} but {len(holders)} holders"
        stray = [h for h in holders if h != DEFAULTS and h not in active]
        if stray:
            return f"{capability} is held by {stray[0]}, which is not active"
    for name in sorted(active):
        needs = executive.specialist.capabilities_of(name)
        if isinstance(needs, str):
            continue
        for capability in needs:
            if name not in manager.holders.get(capability, ()):
                return f"{name} is active without holding {capability}"
    needed = {
        process
        for capability in manager.references
        for process in executive.catalog.capabilities[capability].processes
    }
    running = set(manager.running_processes)
    if running != needed:
        extra = sorted(running - needed)
        if extra:
            return f"process {extra[0]} runs though no referenced capability needs it"
        return f"process {sorted(needed - running)[0]} is needed but not running"
    return ""


def run_mission(bench: Bench, mission: Mission, record: str | Path | None = None) -> Judgement:
    """Run `mission` (recording it to `record` when given) and judge it."""
    text, world = bench.texts(mission)
    script = compile_mission(text, MISSION_NAME)
    monitor = PropertyMonitor(bench.properties)
    invariants = Invariants()
    result = simulate(
        _session(bench, MISSION_NAME, WORLD_NAME, record),
        [monitor, invariants],
        catalog=bench.catalog,
        script=script,
        world=(world, WORLD_NAME),
    )
    return judge(monitor, invariants, result)


def judge(monitor: PropertyMonitor, invariants: Invariants, result: SessionResult) -> Judgement:
    violations = [
        Violation(v.name, v.message(), v.robustness)
        for v in monitor.verdicts
        if v.status == VIOLATED
    ]
    violations += [Violation(name, message) for name, message in sorted(invariants.broken.items())]
    robustness = {
        v.name: v.robustness
        for v in monitor.verdicts
        if v.robustness is not None and math.isfinite(v.robustness)
    }
    return Judgement(tuple(violations), robustness, result)


def run_files(bench: Bench, mission: Path, world: Path, record: Path | None) -> Judgement:
    """Run a written counterexample as `aeroexec run MISSION -w WORLD -o RECORD` does
    (the script and world read from their files), judged as the fuzzer judged it."""
    monitor = PropertyMonitor(bench.properties)
    invariants = Invariants()
    config = _session(bench, mission, world, record)
    return judge(monitor, invariants, simulate(config, [monitor, invariants]))


def _session(
    bench: Bench, mission: str | Path, world: str | Path, record: str | Path | None
) -> SessionConfig:
    """The session every judged run has: the fuzzed catalog's settings, its time limit."""
    target = bench.target
    return SessionConfig(
        mission=mission,
        catalog=target.catalog,
        seed=target.seed,
        world=world,
        record=record,
        behaviors=bench.behaviors,
        allow_unimplemented=target.allow_unimplemented,
        max_sim_time_s=MAX_SIM_TIME_S,
    )
