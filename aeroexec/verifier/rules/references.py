"""AX2xx: references to lists, behaviors and capabilities that are not defined, or
named twice."""

from __future__ import annotations

import itertools
from collections.abc import Callable, Container, Iterator, Sequence

from aeroexec.catalog.model import Severity
from aeroexec.errors import Mark
from aeroexec.verifier.findings import Finding
from aeroexec.verifier.graphs import CatalogGraphs, Definition
from aeroexec.verifier.registry import catalog_rule
from aeroexec.verifier.witness import rejection_witness

E, W = Severity.ERROR, Severity.WARNING


def _replaced(definition: Definition, kind: str) -> str:
    if definition.effective:
        return ""
    return (
        f" (in the first definition of {kind} {definition.item.name}, which the one at "
        f"line {definition.replaced_at} replaces)"
    )


def _kind_of(graphs: CatalogGraphs, name: str, expected: str) -> str | None:
    """What a name is when it is defined, but not as the `expected` kind."""
    catalog = graphs.catalog
    kinds = (
        ("behavior", catalog.behaviors),
        ("list", catalog.lists),
        ("capability", catalog.capabilities),
    )
    for kind, names in kinds:
        if kind != expected and name in names:
            return kind
    return None


def _what_else(graphs: CatalogGraphs, name: str, expected: str) -> str:
    kind = _kind_of(graphs, name, expected)
    return f"it is a {kind}, not a {expected}" if kind else ""


def _dangling(
    definitions: Sequence[Definition], field: str, defined: Container[str]
) -> Iterator[tuple[Definition, int, str]]:
    """(definition, index, name) for each name in the entries' `field` that is not in
    `defined`, at its first place in the entry (a repetition is AX206's): the one loop
    every undefined-reference rule walks."""
    for definition in definitions:
        names = getattr(definition.item, field)
        for name in names:
            if name not in defined:
                break
        else:
            continue  # the usual entry: every name defined, no repeats to look for
        for index, name in _first_places(names):
            if name not in defined:
                yield definition, index, name


def _repeated(names: Sequence[str]) -> set[str]:
    """The names `names` holds more than once. From a sorted copy (eight bytes a name)
    rather than a set of every name: a list can be a million names long."""
    if len(names) <= 64:  # the usual list: a few names, most often none repeated
        if len(set(names)) == len(names):
            return set()
        return {n for i, n in enumerate(names) if n in names[:i]}
    ordered = sorted(names)
    return {a for a, b in itertools.pairwise(ordered) if a == b}


def _first_places(names: Sequence[str]) -> Iterator[tuple[int, str]]:
    """(index, name) for the first place of each name in `names`."""
    repeated = _repeated(names)
    seen: set[str] = set()
    for index, name in enumerate(names):
        if name in repeated:
            if name in seen:
                continue
            seen.add(name)
        yield index, name


def _capability_detail(graphs: CatalogGraphs, name: str) -> str:
    """' (it is a list, not a capability)' or a did-you-mean for an undefined capability."""
    other = _what_else(graphs, name, "capability")
    return f" ({other})" if other else graphs.capability_names.hint(name)


@catalog_rule(
    "AX201",
    "undefined-list",
    E,
    """A behavior's `incompatible_lists` names a list that `behavior_lists` does not
    define (often a misspelling, like the flown catalogs' `self_localizaion_behaviors`).
    The thesis' specialist stops loading the catalog here. In flight: the behavior
    preempts nothing through that list, so the behaviors it was meant to stop keep
    running beside it. Fix: correct the name (the message suggests the closest list) or
    define the list.""",
)
def undefined_list(graphs: CatalogGraphs) -> Iterator[Finding]:
    dangling = _dangling(graphs.behavior_defs, "incompatible_lists", graphs.catalog.lists)
    for definition, index, name in dangling:
        behavior = definition.item
        other = _what_else(graphs, name, "list")
        detail = f"; {other}" if other else graphs.list_names.hint(name)
        yield graphs.finding(
            "AX201",
            E,
            f"{behavior.name}: incompatible list '{name}' is not defined{detail}; "
            f"{behavior.name} preempts nothing through it{_replaced(definition, 'behavior')}",
            behavior.item_mark("incompatible_lists", index),
            (behavior.name, name),
        )


@catalog_rule(
    "AX202",
    "list-member-not-a-behavior",
    E,
    """A behavior list names something that is not a defined behavior: a misspelled or
    removed behavior, or a capability (the thesis' Appendix A lists the capability
    `VISUAL_SERVOING` among `motion_behaviors`). In flight: the behaviors that name the
    list do not preempt the behavior that was meant (a misspelled member leaves the
    real one running). Fix: name the behavior as it is defined, or remove the entry.""",
)
def list_member_not_a_behavior(graphs: CatalogGraphs) -> Iterator[Finding]:
    for definition, index, member in _dangling(
        graphs.list_defs, "behaviors", graphs.catalog.behaviors
    ):
        lst = definition.item
        kind = _kind_of(graphs, member, "behavior")
        if kind:
            message = f"list {lst.name}: {member} is a {kind}, not a behavior"
        else:
            hint = graphs.behavior_names.hint(member)
            message = f"list {lst.name}: {member} is not a defined behavior{hint}"
        yield graphs.finding(
            "AX202",
            E,
            message + _replaced(definition, "list"),
            lst.item_mark("behaviors", index),
            (lst.name, member),
        )


@catalog_rule(
    "AX203",
    "undefined-capability",
    E,
    """A behavior names a capability that `capability_descriptors` does not define. In
    flight: the resource manager cannot activate it, so every activation of the
    behavior is rejected. Fix: define the capability (with its processes) or correct
    the name.""",
    witness=True,
)
def undefined_capability(graphs: CatalogGraphs) -> Iterator[Finding]:
    dangling = _dangling(graphs.behavior_defs, "capabilities", graphs.catalog.capabilities)
    for definition, index, name in dangling:
        behavior = definition.item
        detail = _capability_detail(graphs, name)
        witness = None
        if definition.effective:
            witness = rejection_witness(graphs.model, (behavior.name,), behavior.name)
        yield graphs.finding(
            "AX203",
            E,
            f"{behavior.name}: capability '{name}' is not defined{detail}: every "
            f"activation of {behavior.name} is rejected{_replaced(definition, 'behavior')}",
            behavior.item_mark("capabilities", index),
            (behavior.name, name),
            witness,
        )


@catalog_rule(
    "AX204",
    "undefined-incompatible-capability",
    W,
    """A capability's `incompatible_capabilities` names a capability that is not defined
    (the IMAV 2017 catalogs declare `SETPOINT_BASED_FLIGHT_CONTROL` incompatible with an
    undefined `VISUAL_SERVOING`). In flight: nothing, and that is the problem — the
    conflict it was meant to prevent is not checked against the capability actually
    used. Fix: correct the name or remove the entry.""",
)
def undefined_incompatible_capability(graphs: CatalogGraphs) -> Iterator[Finding]:
    for definition, index, name in _dangling(
        graphs.capability_defs, "incompatible_capabilities", graphs.catalog.capabilities
    ):
        spec = definition.item
        yield graphs.finding(
            "AX204",
            W,
            f"capability {spec.name}: incompatible capability '{name}' is not "
            f"defined{_capability_detail(graphs, name)}; the conflict it declares is never "
            "checked",
            spec.item_mark("incompatible_capabilities", index),
            (spec.name, name),
        )


@catalog_rule(
    "AX205",
    "undefined-required-capability",
    E,
    """A capability's `required_capabilities` names a capability that is not defined
    (flown catalogs kept requiring `SELF_LOCALIZATION_BY_VISUAL_MARKERS` after it was
    removed). The executive starts required capabilities first, so it cannot expand
    the capability. In flight: every behavior that uses it is rejected at activation.
    Fix: define the required capability or remove the requirement.""",
    witness=True,
)
def undefined_required_capability(graphs: CatalogGraphs) -> Iterator[Finding]:
    users: dict[str, tuple[str, ...]] | None = None  # built at the first dangling name
    for definition, index, name in _dangling(
        graphs.capability_defs, "required_capabilities", graphs.catalog.capabilities
    ):
        spec = definition.item
        if users is None:
            users = _users_by_capability(graphs)
        affected = users.get(spec.name, ()) if definition.effective else ()
        witness = None
        if affected:
            consequence = f"; behaviors using it are rejected: {', '.join(affected)}"
            witness = rejection_witness(graphs.model, affected[:1], affected[0])
        else:
            consequence = "; no behavior uses it yet"
        yield graphs.finding(
            "AX205",
            E,
            f"capability {spec.name} requires '{name}', which is not defined"
            f"{_capability_detail(graphs, name)}{consequence}",
            spec.item_mark("required_capabilities", index),
            (spec.name, name, *affected),
            witness,
        )


def _users_by_capability(graphs: CatalogGraphs) -> dict[str, tuple[str, ...]]:
    """Capability -> behaviors (catalog order) that reference it, directly or through
    required capabilities, whether or not the expansion succeeds."""
    capabilities = graphs.catalog.capabilities
    result: dict[str, list[str]] = {}
    for name, behavior in graphs.catalog.behaviors.items():
        reached: set[str] = set()
        stack = [c for c in behavior.capabilities if c in capabilities]
        while stack:
            current = stack.pop()
            if current in reached:
                continue
            reached.add(current)
            stack.extend(
                r for r in capabilities[current].required_capabilities if r in capabilities
            )
        for capability in reached:
            result.setdefault(capability, []).append(name)
    return {k: tuple(v) for k, v in result.items()}


#: The mark of item `index` of list `field` of an entry (`BehaviorDescriptor.item_mark`).
MarkOf = Callable[[str, int], Mark]


def _repeats(
    graphs: CatalogGraphs,
    owner: str,
    subject: str,
    field: str,
    names: Sequence[str],
    mark_of: MarkOf,
) -> Iterator[Finding]:
    if len(names) < 2:
        return
    repeated = _repeated(names)
    if not repeated:
        return
    first: dict[str, int] = {}
    second: dict[str, int] = {}
    count: dict[str, int] = {}
    for index, name in enumerate(names):
        if name in repeated:
            first.setdefault(name, index)
            if index != first[name]:
                second.setdefault(name, index)
            count[name] = count.get(name, 0) + 1
    for name, index in second.items():
        earlier = mark_of(field, first[name])
        at = f" (first at line {earlier.line})" if earlier.line else ""
        times = "twice" if count[name] == 2 else f"{count[name]:,} times"
        yield graphs.finding(
            "AX206",
            W,
            f"{owner}: '{name}' is named {times} in {field}{at}",
            mark_of(field, index),
            (subject, name),
        )


@catalog_rule(
    "AX206",
    "repeated-reference",
    W,
    """The same name appears twice in one reference list: a list's `behaviors`, a
    behavior's `incompatible_lists` or `capabilities`, a capability's `processes`,
    `incompatible_capabilities` or `required_capabilities`. In flight: nothing
    (capabilities are referenced once per behavior, processes started once), but the
    repetition usually hides a different name that was meant, whose effect is missing.
    Reported once per repeated name, at its second place, with how many times it is
    named (an undefined name is reported once too, at its first place). Fix: remove the
    repetition or correct it to the name that was meant.""",
)
def repeated_reference(graphs: CatalogGraphs) -> Iterator[Finding]:
    for b in graphs.behavior_defs:
        behavior = b.item
        for field in ("incompatible_lists", "capabilities"):
            names = getattr(behavior, field)
            yield from _repeats(
                graphs, behavior.name, behavior.name, field, names, behavior.item_mark
            )
    for entry in graphs.list_defs:
        lst = entry.item
        yield from _repeats(
            graphs, f"list {lst.name}", lst.name, "behaviors", lst.behaviors, lst.item_mark
        )
    for c in graphs.capability_defs:
        spec = c.item
        for field in ("processes", "incompatible_capabilities", "required_capabilities"):
            yield from _repeats(
                graphs,
                f"capability {spec.name}",
                spec.name,
                field,
                getattr(spec, field),
                spec.item_mark,
            )
