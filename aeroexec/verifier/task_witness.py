"""Witnesses of task catalogs, checked on the coordinator's model (issue 30, point 6).

`aeroexec run` runs behavior catalogs only: the executive implements the 2017 thesis'
coordinator, not the 2020-2021 task semantics (a constraint search over tasks,
cvar-upm/coordinator_cbc). A witness of a task catalog therefore cannot be run; it is
replayed instead on `task_model.TaskModel`, the model the task rules are written
against, from an idle coordinator, and the output says so: the witness's caveat reads
"replayed on the model of the 2021 task coordinator", or, should the replay not give
the witness's outcome, that it does not hold there.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import replace

from aeroexec.catalog.tasks import TaskCatalog
from aeroexec.verifier.findings import Finding, Outcome, Witness
from aeroexec.verifier.task_model import IDLE, TaskModel

HOLDS = (
    "replayed on the model of the 2021 task coordinator; `aeroexec run` runs behavior catalogs only"
)
FAILS = "does not hold on the model of the 2021 task coordinator"


def replays(model: TaskModel, witness: Witness) -> bool:
    """Whether the witness's start_task steps give its outcome on the model."""
    state = IDLE
    steps = witness.setup + witness.steps
    for index, step in enumerate(steps):
        attempt = model.start_task(state, step.activate)
        last = index == len(steps) - 1
        if attempt.accepted is None:
            return False
        if witness.outcome is Outcome.REJECTED and last:
            return attempt.accepted is False
        if not attempt.accepted:
            return False
        state = attempt.after
    if witness.outcome is Outcome.ALL_ACTIVE:
        running = {task for task, _, _ in state}
        return all(step.activate in running for step in witness.steps)
    return witness.outcome is not Outcome.REJECTED


def checked_on_model(catalog: TaskCatalog, findings: Iterable[Finding]) -> Iterator[Finding]:
    """The findings, each task witness replayed on the model and marked so."""
    model: TaskModel | None = None  # built for the first witness: most findings have none
    for finding in findings:
        witness = finding.witness
        if witness is None or any(s.service != "start_task" for s in witness.steps):
            yield finding
            continue
        model = model or TaskModel(catalog)
        note = HOLDS if replays(model, witness) else FAILS
        caveat = f"{witness.caveat}; {note}" if witness.caveat else note
        yield replace(finding, witness=replace(witness, caveat=caveat))
