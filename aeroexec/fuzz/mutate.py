"""`aeroexec fuzz -m MISSION`: mutate a mission instead of generating from scratch.

The mission is run once in simulation (the user asked for it to run: it is a mission
script given with -m, never a file aeroexec was only asked to read), and the behavior
commands it issued, with the argument values it computed, are its steps. A mutant keeps,
drops, repeats or perturbs (new allowed argument values) each step, swaps a few, and adds
up to two world faults. Dropping is each step's first choice, so Hypothesis shrinks a
mutant that breaks something to the fewest of the mission's own steps that still do.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path
from typing import Any

from hypothesis import strategies as st

from aeroexec.catalog.model import Catalog
from aeroexec.errors import FuzzError, Mark
from aeroexec.executive.messages import ServiceCallRecord, TopicRecord
from aeroexec.fuzz.oracle import MAX_SIM_TIME_S, Bench
from aeroexec.fuzz.steps import ACTIVATE, EXECUTE, INHIBIT, Command, Mission
from aeroexec.fuzz.strategies import Vocabulary, arguments, fault
from aeroexec.mission.session import SessionConfig, simulate

_ACTIONS = {
    "execute_behavior": EXECUTE,
    "activate_behavior": ACTIVATE,
    "inhibit_behavior": INHIBIT,
}
#: A step's fate; the first is where shrinking goes.
_FATES = ("drop", "keep", "keep", "keep", "perturb", "repeat")
MAX_SWAPS = 3
MAX_FAULTS = 2


class _Commands:
    """A bus observer that keeps the mission's behavior commands."""

    def __init__(self, catalog: Catalog) -> None:
        self.catalog = catalog
        self.steps: list[Command] = []

    def on_service_call(self, record: ServiceCallRecord) -> None:
        return None

    def on_topic(self, record: TopicRecord) -> None:
        if record.topic != "mission/command":
            return
        action = _ACTIONS.get(record.data.get("command", ""))
        if action is None:
            return
        behavior = str(record.data.get("behavior", ""))
        given: dict[str, Any] = record.data.get("arguments") or {}
        descriptor = self.catalog.behaviors.get(behavior)
        named = []
        for name, value in given.items():
            spec = descriptor.argument(str(name)) if descriptor is not None else None
            named.append((spec.name if spec is not None else str(name), value))
        self.steps.append(Command(action, behavior, tuple(named)))


def mission_steps(bench: Bench, mission: Path) -> Mission:
    """The behavior commands `mission` issues when it runs (`FuzzError` when none)."""
    observer = _Commands(bench.catalog)
    target = bench.target
    config = SessionConfig(
        mission=mission,
        catalog=target.catalog,
        seed=target.seed,
        behaviors=bench.behaviors,
        allow_unimplemented=target.allow_unimplemented,
        max_sim_time_s=MAX_SIM_TIME_S,
    )
    # What the mission prints is not the fuzzer's output.
    with open(os.devnull, "w", encoding="utf-8") as nowhere, contextlib.redirect_stdout(nowhere):
        simulate(config, [observer], catalog=bench.catalog)
    if not observer.steps:
        raise FuzzError(
            "the mission issues no behavior command: nothing to mutate", Mark(str(mission))
        )
    return tuple(observer.steps)


def _perturbed(catalog: Catalog, step: Command) -> st.SearchStrategy[Command]:
    descriptor = catalog.behaviors.get(step.behavior)
    if descriptor is None or step.action == INHIBIT or not descriptor.arguments:
        return st.just(step)
    return arguments(descriptor).map(lambda a: Command(step.action, step.behavior, a))


def mutations(origin: Mission, catalog: Catalog, words: Vocabulary) -> st.SearchStrategy[Mission]:
    """Mutants of `origin`'s commands (its faults are dropped: a flown mission has none)."""
    steps = [s for s in origin if isinstance(s, Command)]

    def fate(step: Command) -> st.SearchStrategy[tuple[Command, ...]]:
        def become(choice: str) -> st.SearchStrategy[tuple[Command, ...]]:
            if choice == "drop":
                return st.just(())
            if choice == "keep":
                return st.just((step,))
            if choice == "repeat":
                return st.just((step, step))
            return _perturbed(catalog, step).map(lambda s: (s,))

        return st.sampled_from(_FATES).flatmap(become)

    last = max(0, len(steps) - 1)
    swaps = st.lists(st.tuples(st.integers(0, last), st.integers(0, last)), max_size=MAX_SWAPS)
    faults = st.lists(fault(words), max_size=MAX_FAULTS) if words.fault_kinds else st.just([])

    def assemble(
        parts: tuple[tuple[tuple[Command, ...], ...], list[tuple[int, int]], list[Any]],
    ) -> Mission:
        fates, swapped, struck = parts
        slots = list(fates)
        for i, j in swapped:
            slots[i], slots[j] = slots[j], slots[i]
        return tuple(s for slot in slots for s in slot) + tuple(struck)

    return st.tuples(st.tuples(*(fate(s) for s in steps)), swaps, faults).map(assemble)
