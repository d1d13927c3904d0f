"""Witnesses: the shortest activation sequences that make a finding happen.

`ActivationModel` is the executive's activation semantics reduced to sets
(docs/design.md#activation): initiation references the default capabilities (with the
ones they require) and fails if two of them conflict or one cannot be expanded; activating
B is rejected if B is unknown, if one of its capabilities
(expanded with the capabilities they require) is undefined or requires itself, or if
one of its not-yet-referenced capabilities conflicts with another of them or with a
capability still referenced once the behaviors B preempts (its incompatible lists,
and B itself when already active) are gone; otherwise the victims stop and B runs.

`shortest_witness` searches breadth-first over activation sequences drawn from a few
candidate behaviors, so the sequence it returns is the shortest one (ties broken by
the candidates' order) that reaches the goal. Every witness a rule attaches is found
this way, so it is checked against the model before it is shown; the test suite then
replays witnesses in the real executive.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from aeroexec.verifier.findings import Outcome, Step, Witness

if TYPE_CHECKING:
    from aeroexec.verifier.graphs import CatalogGraphs

State = frozenset[str]
EMPTY: State = frozenset()


@dataclass(frozen=True, slots=True)
class Attempt:
    """The result of one modelled activation."""

    behavior: str
    accepted: bool
    before: State
    after: State
    reason: str = ""


class ActivationModel:
    def __init__(self, graphs: CatalogGraphs) -> None:
        self.graphs = graphs
        self.catalog = graphs.catalog

    @property
    def initiation_fails(self) -> bool:
        return bool(self.graphs.default_pairs_in_conflict) or self.graphs.defaults_broken

    def referenced(self, active: State) -> set[str]:
        refs = set() if self.initiation_fails else set(self.graphs.defaults)
        for name in active:
            expansion = self.graphs.expansion(name)
            if expansion:
                refs.update(expansion)
        return refs

    def activate(self, active: State, behavior: str) -> Attempt:
        graphs = self.graphs
        if behavior not in self.catalog.behaviors:
            return Attempt(behavior, False, active, active, "unknown behavior")
        expansion = graphs.expansion(behavior)
        if expansion is None:
            return Attempt(behavior, False, active, active, "capability cannot be expanded")
        victims = {b for b in active if b == behavior or graphs.preempts(behavior, b)}
        remaining = active - victims
        referenced = self.referenced(remaining)
        new = [c for c in expansion if c not in referenced]
        for i, capability in enumerate(new):
            conflicts = self.catalog.conflicts_of(capability)
            if not conflicts:
                continue
            if any(other in conflicts for other in new[:i]):
                return Attempt(behavior, False, active, active, "own capabilities conflict")
            if conflicts & referenced:
                return Attempt(behavior, False, active, active, "conflict with referenced")
        return Attempt(behavior, True, active, remaining | {behavior})


Goal = Callable[[Attempt], bool]


def shortest_witness(
    model: ActivationModel,
    candidates: Sequence[str],
    goal: Goal,
    outcome: Outcome,
    max_depth: int = 3,
) -> Witness | None:
    """Breadth-first search for the shortest sequence whose last activation meets
    `goal` (every earlier activation accepted)."""
    queue: deque[tuple[State, tuple[str, ...]]] = deque([(EMPTY, ())])
    seen = {EMPTY}
    while queue:
        state, path = queue.popleft()
        if len(path) >= max_depth:
            continue
        for behavior in candidates:
            attempt = model.activate(state, behavior)
            if goal(attempt):
                steps = tuple(Step(name) for name in (*path, behavior))
                return Witness(steps, outcome)
            if attempt.accepted and attempt.after not in seen:
                seen.add(attempt.after)
                queue.append((attempt.after, (*path, behavior)))
    return None


def initiation_witness(model: ActivationModel) -> Witness | None:
    return Witness((), Outcome.INITIATION_FAILS) if model.initiation_fails else None


def rejection_witness(
    model: ActivationModel, candidates: Sequence[str], target: str, reason: str | None = None
) -> Witness | None:
    """Shortest sequence ending in a rejected activation of `target` (for `reason`)."""
    if model.initiation_fails:
        return None

    def goal(attempt: Attempt) -> bool:
        return (
            attempt.behavior == target
            and not attempt.accepted
            and (reason is None or attempt.reason == reason)
        )

    return shortest_witness(model, candidates, goal, Outcome.REJECTED)


def coexistence_witness(model: ActivationModel, first: str, second: str) -> Witness | None:
    """Shortest sequence after which both behaviors are active."""
    if model.initiation_fails:
        return None

    def goal(attempt: Attempt) -> bool:
        return attempt.accepted and {first, second} <= attempt.after

    return shortest_witness(model, (first, second), goal, Outcome.ALL_ACTIVE)
