"""AX3xx: capability consistency — conflicts that stop behaviors (or the whole system)
from starting, and capabilities nothing uses."""

from __future__ import annotations

from collections.abc import Iterator

from aeroexec.catalog.model import BehaviorDescriptor, Severity
from aeroexec.errors import Mark
from aeroexec.verifier.findings import Finding
from aeroexec.verifier.graphs import CatalogGraphs
from aeroexec.verifier.registry import catalog_rule
from aeroexec.verifier.witness import initiation_witness, rejection_witness

E, W, INFO = Severity.ERROR, Severity.WARNING, Severity.INFO


def _capability_mark(graphs: CatalogGraphs, behavior: BehaviorDescriptor, capability: str) -> Mark:
    """Where the behavior names `capability` (or the capability that requires it)."""
    if capability in behavior.capabilities:
        return behavior.mark_of(f"capabilities.{behavior.capabilities.index(capability)}")
    for index, direct in enumerate(behavior.capabilities):
        closure = graphs.closure(direct)
        if closure and capability in closure:
            return behavior.mark_of(f"capabilities.{index}")
    return behavior.mark_of("capabilities")


def _via(graphs: CatalogGraphs, behavior: BehaviorDescriptor, capability: str) -> str:
    if capability in behavior.capabilities:
        return capability
    for direct in behavior.capabilities:
        closure = graphs.closure(direct)
        if closure and capability in closure:
            return f"{capability} (required by {direct})"
    return capability


@catalog_rule(
    "AX301",
    "behavior-capabilities-conflict",
    E,
    """Two capabilities of the same behavior (counting the capabilities they require)
    are declared incompatible with each other. In flight: the resource manager rejects
    the behavior's own capability set, so the behavior can never start. Fix: remove one
    capability from the behavior, or drop the incompatibility if both can run
    together.""",
    witness=True,
)
def behavior_capabilities_conflict(graphs: CatalogGraphs) -> Iterator[Finding]:
    for name, behavior in graphs.catalog.behaviors.items():
        pair = graphs.own_conflict(name)
        if pair is None:
            continue
        first, second = pair
        yield graphs.finding(
            "AX301",
            E,
            f"{name} can never start: its capabilities {_via(graphs, behavior, first)} and "
            f"{_via(graphs, behavior, second)} are incompatible",
            _capability_mark(graphs, behavior, second),
            (name, first, second),
            rejection_witness(graphs.model, (name,), name),
        )


@catalog_rule(
    "AX302",
    "default-capabilities-conflict",
    E,
    """Two capabilities that are `active_by_default` are declared incompatible. Default
    capabilities are referenced at initiation and never released. In flight: initiation
    fails, so the executive cannot start at all (the witness is the empty activation
    sequence). Fix: make one of them not active by default, or drop the
    incompatibility.""",
    witness=True,
)
def default_capabilities_conflict(graphs: CatalogGraphs) -> Iterator[Finding]:
    witness = initiation_witness(graphs.model)
    for first, second in graphs.default_pairs_in_conflict:
        yield graphs.finding(
            "AX302",
            E,
            f"default capabilities {first} and {second} are incompatible: initiation "
            "fails and no behavior can run",
            graphs.conflict_mark(second, first),
            (first, second),
            witness,
        )


@catalog_rule(
    "AX303",
    "conflicts-with-default-capability",
    E,
    """A behavior needs a capability that is incompatible with a capability active by
    default. Defaults stay referenced for the whole flight. In flight: every activation
    of the behavior is rejected by the resource manager. Fix: remove the
    incompatibility, make the other capability not active by default, or give the
    behavior a different capability.""",
    witness=True,
)
def conflicts_with_default(graphs: CatalogGraphs) -> Iterator[Finding]:
    if not graphs.defaults:
        return
    for name, behavior in graphs.catalog.behaviors.items():
        pair = graphs.default_conflict(name)
        if pair is None:
            continue
        capability, default = pair
        yield graphs.finding(
            "AX303",
            E,
            f"{name} can never start: its capability {_via(graphs, behavior, capability)} is "
            f"incompatible with {default}, which is active by default",
            _capability_mark(graphs, behavior, capability),
            (name, capability, default),
            rejection_witness(graphs.model, (name,), name),
        )


@catalog_rule(
    "AX304",
    "undeclared-capability-conflict",
    E,
    """Two behaviors use incompatible capabilities, but the one activated second does
    not preempt the first (it is not in one of the second's `incompatible_lists`). In
    flight: instead of a clean preemption (the first behavior stops with INTERRUPTED),
    the second activation is rejected by the resource manager while the first keeps
    running. Fix: put the behaviors in each other's incompatible lists (usually a shared
    list such as `motion_behaviors`).""",
    witness=True,
)
def undeclared_capability_conflict(graphs: CatalogGraphs) -> Iterator[Finding]:
    catalog = graphs.catalog
    holders = graphs.holders
    activatable = graphs.activatable
    defaults = set(graphs.defaults)
    order = catalog.order_of
    # Unordered behavior pair -> conflicting capability pairs (a of first, b of second).
    # Per conflict edge and per holder b of one side, the holders of the other side
    # that b does not both preempt and get preempted by: set operations, no pair loop
    # over behaviors that are declared incompatible.
    pairs: dict[tuple[str, str], list[tuple[str, str]]] = {}
    holder_sets = {c: frozenset(h) & activatable for c, h in holders.items()}
    for a_cap, b_cap in graphs.conflict_pairs:
        if a_cap in defaults or b_cap in defaults:
            continue  # AX302 / AX303
        a_holders = holder_sets.get(a_cap)
        if not a_holders:
            continue
        for b in holders.get(b_cap, ()):
            if b not in activatable:
                continue
            for a in a_holders - graphs.mutual(b):
                if a == b:
                    continue
                if order(a) < order(b):
                    pairs.setdefault((a, b), []).append((a_cap, b_cap))
                else:
                    pairs.setdefault((b, a), []).append((b_cap, a_cap))

    def by_order(item: tuple[tuple[str, str], list[tuple[str, str]]]) -> tuple[int, int]:
        return order(item[0][0]), order(item[0][1])

    for (first, second), found in sorted(pairs.items(), key=by_order):
        caps = sorted(set(found))
        failing = [
            (x, y) for x, y in ((first, second), (second, first)) if not graphs.preempts(y, x)
        ]
        x, y = failing[0]
        x_cap, y_cap = caps[0] if x == first else caps[0][::-1]
        orders = " or ".join(f"{b} while {a} runs" for a, b in failing)
        message = (
            f"{x} ({x_cap}) and {y} ({y_cap}) use incompatible capabilities but are not "
            f"declared incompatible: activating {orders} is rejected"
        )
        subjects = [first, second]
        for pair in caps:
            subjects.extend(pair)
        second_descriptor = catalog.behaviors[y]
        yield graphs.finding(
            "AX304",
            E,
            message,
            _capability_mark(graphs, second_descriptor, y_cap),
            subjects,
            rejection_witness(graphs.model, (x, y), y),
        )


@catalog_rule(
    "AX305",
    "self-incompatible-capability",
    W,
    """A capability lists itself in `incompatible_capabilities`. In flight: the
    executive ignores the entry within one behavior's own capability set, so the
    declaration does nothing except confuse whoever reads it (if the intent was "only
    one behavior at a time may use it", that is what incompatible lists are for). Fix:
    remove the entry.""",
)
def self_incompatible_capability(graphs: CatalogGraphs) -> Iterator[Finding]:
    for definition in graphs.capability_defs:
        spec = definition.item
        if spec.name in spec.incompatible_capabilities:
            index = spec.incompatible_capabilities.index(spec.name)
            yield graphs.finding(
                "AX305",
                W,
                f"capability {spec.name} is declared incompatible with itself",
                spec.mark_of(f"incompatible_capabilities.{index}"),
                (spec.name,),
            )


@catalog_rule(
    "AX306",
    "dead-capability",
    INFO,
    """A capability that no behavior uses (directly or through `required_capabilities`)
    and that is not active by default. In flight: its processes never start — harmless,
    but often the trace of a renamed capability whose behaviors now miss it. Fix: remove
    it, or name it where it is needed.""",
)
def dead_capability(graphs: CatalogGraphs) -> Iterator[Finding]:
    used: set[str] = set(graphs.defaults)
    capabilities = graphs.catalog.capabilities
    stack = [c for b in graphs.catalog.behaviors.values() for c in b.capabilities]
    stack.extend(r for d in graphs.defaults for r in capabilities[d].required_capabilities)
    while stack:
        name = stack.pop()
        if name in used or name not in capabilities:
            continue
        used.add(name)
        stack.extend(capabilities[name].required_capabilities)
    for name, spec in capabilities.items():
        if name not in used:
            yield graphs.finding(
                "AX306",
                INFO,
                f"capability {name} is never used: no behavior needs it and it is not "
                "active by default",
                spec.mark,
                (name,),
            )
