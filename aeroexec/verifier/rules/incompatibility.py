"""AX4xx: incompatibility — one-sided preemption, its cycles, and lists with no effect."""

from __future__ import annotations

from collections.abc import Iterator

from aeroexec.catalog.model import Severity
from aeroexec.verifier.cycles import cycle_edges, cyclic_components, shortest_cycle
from aeroexec.verifier.findings import Finding, Witness
from aeroexec.verifier.graphs import CatalogGraphs
from aeroexec.verifier.registry import catalog_rule
from aeroexec.verifier.witness import EMPTY, coexistence_witness

W = Severity.WARNING

_SHOWN = 8


def _names(names: tuple[str, ...] | list[str]) -> str:
    if len(names) <= _SHOWN:
        return ", ".join(names)
    return ", ".join(names[:_SHOWN]) + f" and {len(names) - _SHOWN} more"


@catalog_rule(
    "AX401",
    "asymmetric-incompatibility",
    W,
    """Behavior A preempts behavior B (B is in one of A's `incompatible_lists`) but B
    does not preempt A. In flight: the outcome depends on activation order —
    activating A stops B, but activating B while A runs leaves both running (the
    witness shows that order). Reported once per behavior that preempts nothing back
    (typically a behavior added to a list without `incompatible_lists` of its own),
    otherwise once per preempting behavior. Fix: make the relation symmetric (put A in
    a list that B names, typically by having both name the same list), or document why
    A alone must win.""",
    witness=True,
)
def asymmetric_incompatibility(graphs: CatalogGraphs) -> Iterator[Finding]:
    catalog = graphs.catalog
    order = catalog.order_of
    one_sided = graphs.asymmetric_preemption
    # Behaviors that preempt nothing (but themselves) are reported as victims, once.
    inert = {
        b
        for victims in one_sided.values()
        for b in victims
        if not (catalog.preempted_by(b) & catalog.behaviors.keys()) - {b}
    }
    attackers: dict[str, list[str]] = {}
    for a, victims in one_sided.items():
        for b in victims:
            if b in inert:
                attackers.setdefault(b, []).append(a)
    for b in sorted(attackers, key=order):
        preemptors = sorted(attackers[b], key=order)
        descriptor = catalog.behaviors[b]
        mark = descriptor.mark_of("incompatible_lists")
        lists = sorted(
            {
                lst
                for a in preemptors
                if (found := graphs.preempting_list(a, b))
                for lst in found[1:]
            }
        )
        plural = len(preemptors) > 1
        consequence = _consequence(
            graphs, preemptors, b, f"after {'one of them' if plural else preemptors[0]}"
        )
        yield graphs.finding(
            "AX401",
            W,
            f"{b} is preempted by {_names(preemptors)} (list {', '.join(lists)}) but "
            f"{'preempts none of them' if plural else 'does not preempt it'}: "
            f"{consequence}",
            mark,
            (b, *preemptors),
            _witness(graphs, [(a, b) for a in preemptors]),
        )
    for a, all_victims in one_sided.items():
        victims = tuple(b for b in all_victims if b not in inert)
        if not victims:
            continue
        descriptor = catalog.behaviors[a]
        through = graphs.preempting_list(a, victims[0])
        index, list_name = through if through is not None else (0, "")
        plural = len(victims) > 1
        message = (
            f"{a} preempts {_names(victims)} (list {list_name}) but "
            f"{'they do' if plural else 'it does'} not preempt {a}: "
            + _victims_consequence(graphs, a, victims)
        )
        yield graphs.finding(
            "AX401",
            W,
            message,
            descriptor.mark_of(f"incompatible_lists.{index}"),
            (a, *victims),
            _witness(graphs, [(a, b) for b in victims]),
        )


def _after(graphs: CatalogGraphs, first: str, second: str) -> str | None:
    """What activating `second` while `first` runs does, on the activation model:
    None when both run, else why `second` does not start beside `first`."""
    model = graphs.model
    started = model.activate(EMPTY, first)
    if not started.accepted:
        return f"{first} can never start"
    attempt = model.activate(started.after, second)
    if attempt.accepted:
        return None if first in attempt.after else f"{second} stops {first}"
    if attempt.reason == "conflict with referenced":
        return f"{second} is rejected (its capabilities conflict with {first}'s)"
    return f"{second} can never start"


def _consequence(graphs: CatalogGraphs, preemptors: list[str], victim: str, when: str) -> str:
    """The claim about activating `victim` after its preemptors, checked on the model."""
    outcomes = {a: _after(graphs, a, victim) for a in preemptors}
    beside = [a for a, why in outcomes.items() if why is None]
    if len(beside) == len(preemptors):
        return f"activated {when}, {victim} runs beside it"
    others = [f"after {a}, {why}" for a, why in outcomes.items() if why is not None]
    if not beside:
        return "they never run together (" + "; ".join(others[:_SHOWN]) + ")"
    return f"activated after {_names(beside)}, {victim} runs beside it; " + "; ".join(
        others[:_SHOWN]
    )


def _victims_consequence(graphs: CatalogGraphs, attacker: str, victims: tuple[str, ...]) -> str:
    outcomes = {b: _after(graphs, attacker, b) for b in victims}
    beside = [b for b, why in outcomes.items() if why is None]
    plural = len(beside) > 1
    if len(beside) == len(victims):
        return f"activated after {attacker}, {'they run' if plural else 'it runs'} beside it"
    others = [why for why in outcomes.values() if why is not None]
    if not beside:
        return f"they never run together (after {attacker}: " + "; ".join(others[:_SHOWN]) + ")"
    return (
        f"activated after {attacker}, {_names(beside)} {'run' if plural else 'runs'} beside "
        f"it; " + "; ".join(others[:_SHOWN])
    )


def _witness(graphs: CatalogGraphs, pairs: list[tuple[str, str]]) -> Witness | None:
    """Both running, for the first (preemptor, victim) pair where that can happen."""
    for a, b in pairs:
        if a in graphs.activatable and b in graphs.activatable:
            witness = coexistence_witness(graphs.model, a, b)
            if witness is not None:
                return witness
    return None


@catalog_rule(
    "AX402",
    "asymmetric-incompatibility-cycle",
    W,
    """A cycle of one-sided preemptions: A preempts B, B preempts C, ... and the last
    preempts A, none of them preempted back. In flight: which behavior survives a
    sequence of activations depends on their order in a way nobody can keep in mind
    (rock-paper-scissors). Fix: make the incompatibilities along the cycle symmetric,
    or break the cycle.""",
)
def asymmetric_incompatibility_cycle(graphs: CatalogGraphs) -> Iterator[Finding]:
    if not graphs.asymmetric_preemption:
        return  # no edge, no cycle: the graph need not be built
    graph = graphs.asymmetric_preemption_graph
    order = graphs.catalog.order_of
    components = [c for c in cyclic_components(graph) if len(c) > 1]
    components.sort(key=lambda c: min(order(n) for n in c))
    for component in components:
        cycle = shortest_cycle(graph, component, order)
        steps = []
        for a, b in cycle_edges(cycle):
            through = graphs.preempting_list(a, b)
            steps.append(f"{a} preempts {b}" + (f" (list {through[1]})" if through else ""))
        extra = len(component) - (len(cycle) - 1)
        more = f"; {extra} more behaviors are in the same cycle set" if extra > 0 else ""
        start = graphs.catalog.behaviors[cycle[0]]
        through = graphs.preempting_list(cycle[0], cycle[1])
        yield graphs.finding(
            "AX402",
            W,
            "one-sided preemption cycle: " + ", ".join(steps) + more,
            start.mark_of(f"incompatible_lists.{through[0] if through else 0}"),
            sorted(component, key=order),
        )


@catalog_rule(
    "AX403",
    "dead-list",
    W,
    """A behavior list that no behavior names in `incompatible_lists`. Lists exist only
    to be named there. In flight: it has no effect at all, often because the name that
    was meant to reach it is misspelled (the flown catalogs' `self_localization_behaviors`
    is dead because behaviors name `self_localizaion_behaviors`), so the preemption it
    describes never happens. Fix: name it where it was meant, or remove it.""",
)
def dead_list(graphs: CatalogGraphs) -> Iterator[Finding]:
    named = graphs.list_namers
    lists = graphs.catalog.lists
    dead = [name for name in lists if name not in named]
    if not dead:
        return
    # Dead list -> the first undefined name (catalog order) that looks like it, and
    # the behaviors that name that one.
    misspelt: dict[str, str] = {}
    for behavior in graphs.catalog.behaviors.values():
        for name in behavior.incompatible_lists:
            if name not in lists:
                close = graphs.list_names.best(name)
                if close is not None and close not in misspelt:
                    misspelt[close] = name
    wrong_namers: dict[str, list[str]] = {wrong: [] for wrong in misspelt.values()}
    for behavior_name, behavior in graphs.catalog.behaviors.items():
        named = {n for n in behavior.incompatible_lists if n in wrong_namers}
        for name in behavior.incompatible_lists:
            if name in named:
                named.discard(name)
                wrong_namers[name].append(behavior_name)
    for name in dead:
        lst = lists[name]
        hint = ""
        if name in misspelt:
            wrong = misspelt[name]
            namers = tuple(wrong_namers[wrong])
            verb = "names" if len(namers) == 1 else "name"
            hint = f" ({_names(namers)} {verb} '{wrong}': a misspelling of it?)"
        yield graphs.finding(
            "AX403",
            W,
            f"list {name} is not named in any behavior's incompatible_lists, so it has no "
            f"effect{hint}",
            lst.mark,
            (name,),
        )


@catalog_rule(
    "AX404",
    "empty-list",
    W,
    """A behavior list with no behaviors. In flight: naming it in `incompatible_lists`
    preempts nothing. Fix: fill it or remove it.""",
)
def empty_list(graphs: CatalogGraphs) -> Iterator[Finding]:
    for definition in graphs.list_defs:
        lst = definition.item
        if not lst.behaviors:
            yield graphs.finding(
                "AX404",
                W,
                f"list {lst.name} has no behaviors",
                lst.mark_of("behaviors"),
                (lst.name,),
            )
