"""Hypothesis strategies for missions, drawn from a catalog.

Each command names a catalog behavior: execute (non-recurrent ones only: executing a
recurrent one never returns, and the API refuses it), activate or inhibit. Its arguments
are a subset of the behavior's declared ones, each with a value the catalog allows, the
boundaries drawn as often as the inside. Faults are the simulator's kinds
(`vehicles.world.FAILURE_KINDS`, enumerated, so a kind added there is fuzzed too) at a
tick of the first `FAULT_WINDOW_DS`. Hypothesis shrinks toward fewer steps, the first
behaviors of the catalog, the lower boundary and earlier faults.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from hypothesis import strategies as st

from aeroexec.catalog.model import ArgumentKind, ArgumentSpec, BehaviorDescriptor, Catalog
from aeroexec.fuzz.steps import ACTIVATE, EXECUTE, INHIBIT, Command, Fault, Mission
from aeroexec.vehicles import world

#: The generated part of a mission has at most this many steps (the ending adds its own).
MAX_STEPS = 12
#: Faults strike within the first minute of the session.
FAULT_WINDOW_DS = 600
#: Text arguments get one of these (the catalog says nothing about their values).
TEXTS = ("", "a", "marker")


@dataclass(frozen=True, slots=True)
class Vocabulary:
    """What a mission of one catalog may say."""

    behaviors: tuple[str, ...]
    executable: tuple[str, ...]
    fault_kinds: tuple[str, ...]


def vocabulary(catalog: Catalog, fault_kinds: tuple[str, ...] | None = None) -> Vocabulary:
    names = tuple(catalog.behaviors)
    executable = tuple(n for n in names if not catalog.behaviors[n].recurrent)
    # Read at each call: a kind the simulator gains is fuzzed without a change here.
    kinds = world.FAILURE_KINDS if fault_kinds is None else fault_kinds
    return Vocabulary(names, executable, tuple(kinds))


def _number(minimum: float, maximum: float) -> st.SearchStrategy[Any]:
    if float(minimum).is_integer() and float(maximum).is_integer():
        low, high = int(minimum), int(maximum)
        inside = st.integers(low, high)
        edges: list[Any] = [low, high]
    else:
        inside = st.floats(minimum, maximum, allow_nan=False, allow_infinity=False)
        edges = [float(minimum), float(maximum)]
    if minimum < 0 < maximum:
        edges.insert(0, 0)
    return st.one_of(st.sampled_from(edges), inside)


def value(spec: ArgumentSpec) -> st.SearchStrategy[Any] | None:
    """A value `spec` allows (None: nothing does, a malformed specification)."""
    if spec.kind is ArgumentKind.SYMBOLS and spec.symbols:
        return st.sampled_from(spec.symbols)
    if spec.kind is ArgumentKind.TEXT:
        return st.sampled_from(TEXTS)
    if spec.kind is ArgumentKind.RANGE and spec.minimum is not None and spec.maximum is not None:
        number = _number(spec.minimum, spec.maximum)
        if spec.dimensions == 1:
            return number
        return st.lists(number, min_size=spec.dimensions, max_size=spec.dimensions)
    return None


def arguments(descriptor: BehaviorDescriptor) -> st.SearchStrategy[tuple[tuple[str, Any], ...]]:
    """A subset of the behavior's arguments (each at most once), with allowed values."""
    usable = [(spec.name, value(spec)) for spec in descriptor.arguments]
    usable = [(name, strategy) for name, strategy in usable if strategy is not None]
    if not usable:
        return st.just(())
    chosen = [
        st.one_of(st.none(), strategy.map(lambda v, n=name: (n, v)))  # type: ignore[misc]
        for name, strategy in usable
    ]
    return st.tuples(*chosen).map(lambda pairs: tuple(p for p in pairs if p is not None))


def command(catalog: Catalog, words: Vocabulary) -> st.SearchStrategy[Command]:
    def with_arguments(action: str, name: str) -> st.SearchStrategy[Command]:
        return arguments(catalog.behaviors[name]).map(lambda a: Command(action, name, a))

    strategies = []
    if words.executable:
        strategies.append(
            st.sampled_from(words.executable).flatmap(lambda n: with_arguments(EXECUTE, n))
        )
    strategies.append(
        st.sampled_from(words.behaviors).flatmap(lambda n: with_arguments(ACTIVATE, n))
    )
    strategies.append(st.sampled_from(words.behaviors).map(lambda n: Command(INHIBIT, n)))
    return st.one_of(strategies)


def fault(words: Vocabulary) -> st.SearchStrategy[Fault]:
    return st.builds(Fault, st.sampled_from(words.fault_kinds), st.integers(0, FAULT_WINDOW_DS))


def take_off_behavior(catalog: Catalog) -> str | None:
    """The behavior a mission takes off with: TAKE_OFF, else the first non-recurrent one
    whose name starts with TAKE_OFF (catalog order)."""
    for name, behavior in catalog.behaviors.items():
        if (
            name.startswith("TAKE_OFF")
            and not behavior.recurrent
            and (name == "TAKE_OFF" or "TAKE_OFF" not in catalog.behaviors)
        ):
            return name
    return None


def missions(
    catalog: Catalog, words: Vocabulary, max_steps: int = MAX_STEPS
) -> st.SearchStrategy[Mission]:
    """Missions of up to `max_steps` steps, commands three times as likely as faults.
    Three in four begin by taking off (most behaviors need a flying vehicle), which
    shrinking drops when the violation does not need it."""
    step: st.SearchStrategy[Any] = command(catalog, words)
    if words.fault_kinds:
        step = st.one_of(step, step, step, fault(words))
    take_off = take_off_behavior(catalog)
    first = st.sampled_from((False, True, True, True)) if take_off else st.just(False)

    def assemble(parts: tuple[bool, list[Any]]) -> Mission:
        flies, rest = parts
        head = (Command(EXECUTE, take_off),) if flies and take_off else ()
        return head + tuple(rest[: max_steps - len(head)])

    return st.tuples(first, st.lists(step, max_size=max_steps)).map(assemble)
