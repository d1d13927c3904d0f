"""Witnesses run with the real behaviors, in the real executive.

A witness (`aeroexec.verifier.witness`) is found on the catalog model, where only the
catalog decides. The real behaviors also check their situation first: GO_TO_POINT is
refused on the ground, so "activate GO_TO_POINT, then FOLLOW_OBJECT_IMAGE" shows its
capability conflict only once the drone flies. `realize` completes a witness for a set
of implementations:

* **setup**: behaviors run to their end before the witness (at most `MAX_SETUP`, drawn
  from the catalog's goal-based behaviors that have real code, in catalog order, the
  shortest that works first), so that every step's situation holds — TAKE_OFF before a
  motion behavior;
* **arguments** for each step, from the catalog's argument specs (none, all, then each
  one alone), so that `on_start` accepts the activation and the behavior stays active.

`run` replays a witness in an `Executive` (simulated vehicle in the default world,
simulated clock) and says what went differently, if anything: a step refused or ended,
a rejection for another reason than the model's (the reason is checked, not only that
it failed). Catalog behaviors without an implementation run as explicit stand-ins
(`GenericBehavior`), which always allow their activation.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

from aeroexec.catalog.model import ArgumentKind, ArgumentSpec, BehaviorDescriptor, Catalog
from aeroexec.executive.behavior import Behavior, GenericBehavior
from aeroexec.executive.clock import SimClock
from aeroexec.executive.executive import Executive
from aeroexec.executive.messages import EventCode
from aeroexec.verifier.findings import Finding, Outcome, Step, Witness
from aeroexec.verifier.graphs import CatalogGraphs
from aeroexec.verifier.witness import EMPTY, ActivationModel

Library = Mapping[str, type[Behavior]]

#: How many behaviors a setup may run before the witness.
MAX_SETUP = 1
#: A setup behavior must end within this much simulated time (s) when the catalog sets
#: no timeout.
SETUP_LIMIT_S = 60.0

#: The model's rejection reasons, and how the executive words each one.
REASONS: Mapping[str, re.Pattern[str]] = {
    "unknown behavior": re.compile(r"^unknown behavior "),
    "capability cannot be expanded": re.compile(r"(is not defined|requires itself)"),
    "own capabilities conflict": re.compile(r"capabilities \S+ and \S+ conflict"),
    "conflict with referenced": re.compile(r"conflicts with active capability \S+"),
}


class WitnessMismatch(Exception):
    """The executive did not do what the witness says (the message says what it did)."""


@dataclass(frozen=True, slots=True)
class WitnessRun:
    """A witness that ran as it says: the executive after it, and the final activation's
    error (REJECTED witnesses)."""

    executive: Executive
    error: str = ""


def model_reason(catalog: Catalog, witness: Witness) -> str:
    """Why the catalog model rejects the last step of a REJECTED witness ('' for the
    other outcomes)."""
    if witness.outcome is not Outcome.REJECTED:
        return ""
    model = ActivationModel(CatalogGraphs(catalog))
    state = EMPTY
    for step in witness.steps[:-1]:
        state = model.activate(state, step.activate).after
    return model.activate(state, witness.steps[-1].activate).reason


def explains(reason: str, error: str) -> bool:
    """Does the executive's `error` say the model's `reason`?"""
    pattern = REASONS.get(reason)
    return pattern is not None and pattern.search(error) is not None


def _executive(catalog: Catalog, library: Library) -> Executive:
    from aeroexec.vehicles.sim import SimVehicle

    return Executive(
        catalog,
        vehicle=SimVehicle(),
        clock=SimClock(),
        library=library,
        stand_in=GenericBehavior,
    )


def _set_up(executive: Executive, step: Step) -> None:
    name = step.activate
    result = executive.activate_behavior(name, dict(step.arguments))
    if not result.ok:
        raise WitnessMismatch(f"setup {name} was refused: {result.error}")
    uid = result.payload.get("uid")
    descriptor = executive.catalog.behaviors[name]
    limit = descriptor.timeout if descriptor.timeout is not None else SETUP_LIMIT_S
    executive.run_until(lambda: name not in executive.active_behaviors, limit + 1.0)
    ends = [e for e in executive.events if e.uid == uid]
    if not ends or ends[-1].code is not EventCode.GOAL_ACHIEVED:
        ended = f"{ends[-1].code.value} ({ends[-1].detail})" if ends else "did not end"
        raise WitnessMismatch(f"setup {name}: {ended}")
    if executive.active_behaviors:
        raise WitnessMismatch(f"setup {name} left {', '.join(executive.active_behaviors)} active")


def _situation(executive: Executive, name: str) -> None:
    behavior = executive.behaviors.get(name)
    if behavior is None:
        return  # unknown: the activation itself says so
    verdict = behavior.situation()
    if not verdict.ok:
        raise WitnessMismatch(f"situation: {verdict.error}")


def run(
    catalog: Catalog, witness: Witness, library: Library, reason: str | None = None
) -> WitnessRun:
    """Replay `witness` (its setup, then its steps) in a real executive with `library`;
    `WitnessMismatch` when it does not end as it says. `reason`: the model's rejection
    reason to check the executive's error against (default: computed)."""
    executive = _executive(catalog, library)
    if witness.outcome is Outcome.INITIATION_FAILS:
        if executive.initiation.ok or witness.steps:
            raise WitnessMismatch("initiation did not fail")
        return WitnessRun(executive, executive.initiation.error)
    for step in witness.setup:
        _situation(executive, step.activate)
        _set_up(executive, step)
    *prefix, last = witness.steps
    for step in prefix:
        _situation(executive, step.activate)
        result = executive.activate_behavior(step.activate, dict(step.arguments))
        if not result.ok:
            raise WitnessMismatch(f"step {step.activate} was rejected: {result.error}")
        if step.activate not in executive.active_behaviors:
            raise WitnessMismatch(f"step {step.activate} ended at once: {_last_end(executive)}")
    _situation(executive, last.activate)
    result = executive.activate_behavior(last.activate, dict(last.arguments))
    if witness.outcome is Outcome.REJECTED:
        if result.ok:
            active = ", ".join(executive.active_behaviors)
            raise WitnessMismatch(f"{last.activate} was accepted (active: {active})")
        expected = reason if reason is not None else model_reason(catalog, witness)
        if not explains(expected, result.error):
            raise WitnessMismatch(
                f"{last.activate} was rejected for another reason than {expected!r}: {result.error}"
            )
        return WitnessRun(executive, result.error)
    if not result.ok:
        raise WitnessMismatch(f"{last.activate} was rejected: {result.error}")
    gone = [s.activate for s in witness.steps if s.activate not in executive.active_behaviors]
    if gone:
        raise WitnessMismatch(f"{', '.join(dict.fromkeys(gone))} not active at the end")
    return WitnessRun(executive)


def _last_end(executive: Executive) -> str:
    if not executive.events:
        return "no event"
    event = executive.events[-1]
    return f"{event.code.value} ({event.detail})"


# -- completing a witness for real behaviors -------------------------------------------------
def _sample(spec: ArgumentSpec) -> Any:
    """A value the catalog accepts for `spec` (None when it accepts none)."""
    if spec.kind is ArgumentKind.SYMBOLS:
        return spec.symbols[0] if spec.symbols else None
    if spec.kind is ArgumentKind.TEXT:
        return "witness"
    if spec.kind is not ArgumentKind.RANGE or spec.minimum is None or spec.maximum is None:
        return None
    low, high = spec.minimum, spec.maximum
    value = 0.0 if low <= 0.0 <= high else low
    if float(low).is_integer() and float(high).is_integer():
        value = int(value)
    return value if spec.dimensions == 1 else [value] * spec.dimensions


def argument_choices(descriptor: BehaviorDescriptor, cls: type[Behavior] | None) -> list[Step]:
    """Activations of `descriptor` to try, in order: no arguments, every argument, each
    argument alone (only the arguments the implementation declares it reads, when it
    declares them)."""
    declared = None if cls is None else cls.argument_names
    reads = None if declared is None else {n.casefold() for n in declared}
    values = {
        spec.name: value
        for spec in descriptor.arguments
        if (reads is None or spec.name.casefold() in reads) and (value := _sample(spec)) is not None
    }
    choices: list[dict[str, Any]] = [{}]
    if values:
        choices.append(dict(values))
        choices.extend({name: value} for name, value in values.items())
    seen: set[str] = set()
    steps = []
    for arguments in choices:
        key = repr(sorted(arguments.items()))
        if key not in seen:
            seen.add(key)
            steps.append(Step(descriptor.name, tuple(sorted(arguments.items()))))
    return steps


def _setups(catalog: Catalog, library: Library) -> Iterator[tuple[Step, ...]]:
    yield ()
    if MAX_SETUP < 1:
        return
    for name, descriptor in catalog.behaviors.items():
        cls = library.get(name)
        if cls is None or descriptor.recurrent:
            continue
        for step in argument_choices(descriptor, cls)[:1]:
            yield (step,)


def realize(catalog: Catalog, witness: Witness, library: Library) -> Witness:
    """`witness` with the setup and arguments that make it happen with `library` (the
    same witness when it already does); if nothing within the bounds does, the witness
    as it was with a `caveat` saying what stopped the first attempt."""
    if witness.outcome is Outcome.INITIATION_FAILS:
        return witness
    reason = model_reason(catalog, witness)
    first_problem = ""
    for setup in _setups(catalog, library):
        found = _with_arguments(catalog, replace(witness, setup=setup), library, reason)
        if isinstance(found, Witness):
            return found
        first_problem = first_problem or found
    return replace(witness, caveat=f"not reproduced with the real behaviors: {first_problem}")


def _with_arguments(
    catalog: Catalog, witness: Witness, library: Library, reason: str
) -> Witness | str:
    """Choose each step's arguments in turn (the first that keeps the witness going);
    the completed witness, or what went wrong."""
    steps: list[Step] = []
    for index, step in enumerate(witness.steps):
        descriptor = catalog.behaviors.get(step.activate)
        choices = (
            [step]
            if step.arguments or descriptor is None
            else argument_choices(descriptor, library.get(step.activate))
        )
        problem = ""
        for choice in choices:
            attempt = replace(witness, steps=(*steps, choice))
            if index < len(witness.steps) - 1:
                attempt = replace(attempt, outcome=Outcome.ALL_ACTIVE)
            try:
                run(catalog, attempt, library, reason if attempt.outcome is witness.outcome else "")
            except WitnessMismatch as exc:
                problem = problem or str(exc)
                continue
            steps.append(choice)
            break
        else:
            return problem
    return replace(witness, steps=tuple(steps))


def realize_findings(
    catalog: Catalog, findings: Sequence[Finding], library: Library
) -> list[Finding]:
    """The findings with their witnesses completed for `library` (see `realize`)."""
    return [
        f if f.witness is None else replace(f, witness=realize(catalog, f.witness, library))
        for f in findings
    ]
