"""The 2021 task coordinator's `start_task`, reduced to sets: witnesses for task catalogs.

cvar-upm/coordinator_cbc answers `start_task(T, priority)` by a constraint search over
every task's *domain* (the behaviors that may perform it, or "inactive"), after
`initializeSearch`:

* a running task of higher priority keeps its behavior;
* a running task of lower or equal priority may keep its behavior, take another, or stop;
* a task that is not running and is `start_on_request` stays inactive (only a request
  starts it — requirements do not);
* any other task may be started for a requirement;
* T itself must take one of its behaviors.

Constraints: the tasks of a `mutually_exclusive` set are never active together; a
behavior's required tasks are active while it is, each performed with at least the
requirement's `minimum_performance` (a behavior's suitability; the model does not
multiply it along the chain). The request is rejected when no assignment exists.

`TaskModel.start_task` finds an assignment by depth-first search (T first, then what
each chosen behavior requires, most suitable behavior first) and says why none exists.
It decides feasibility the way the coordinator does; which of several feasible
assignments the coordinator prefers (it maximizes performance) only matters for the
state after an accepted step, and the witnesses this module builds need no more than
one accepted step before the rejected one.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

from aeroexec.catalog.tasks import TaskBehavior, TaskCatalog

#: (task, behavior, priority) of every running task, as a hashable state.
TaskState = frozenset[tuple[str, str, int]]
IDLE: TaskState = frozenset()
#: Search nodes per request; beyond that the answer is "unknown" (None).
BUDGET = 20_000
MISSION_PRIORITY = 2  # what the mission API asks with (2021 Python API)


@dataclass(frozen=True, slots=True)
class TaskAttempt:
    task: str
    #: True accepted, False rejected, None undecided within the search budget.
    accepted: bool | None
    before: TaskState
    after: TaskState
    reason: str = ""


class _OutOfBudget(Exception):
    pass


class TaskModel:
    """`on_request_blocks=False` lets requirements start `start_on_request` tasks too:
    "could this ever start, whatever was requested before?"."""

    def __init__(self, catalog: TaskCatalog, *, on_request_blocks: bool = True) -> None:
        self.catalog = catalog
        self.on_request_blocks = on_request_blocks
        # One candidate per behavior name (the coordinator starts behaviors by name).
        self._candidates: dict[str, tuple[TaskBehavior, ...]] = {}
        for behavior in catalog.behaviors:
            if behavior.task is None:
                continue
            known = self._candidates.setdefault(behavior.task, ())
            if all(b.name != behavior.name for b in known):
                self._candidates[behavior.task] = (*known, behavior)

    def candidates(self, task: str) -> tuple[TaskBehavior, ...]:
        return self._candidates.get(task, ())

    # -- the service ---------------------------------------------------------------------
    def start_task(
        self, state: TaskState, task: str, priority: int = MISSION_PRIORITY
    ) -> TaskAttempt:
        running = {t: (b, p) for t, b, p in state}
        if not self.candidates(task):
            why = (
                f"no behavior performs {task}"
                if task in self.catalog.tasks
                else f"{task} is not a task of the catalog"
            )
            return TaskAttempt(task, False, state, state, why)
        if task in running and running[task][1] > priority:
            return TaskAttempt(task, False, state, state, f"{task} runs at a higher priority")
        search = _Search(self, running, priority)
        fixed = {t: b for t, (b, p) in running.items() if p > priority}
        try:
            found = next(search.assign(task, fixed, True), None)
        except _OutOfBudget:
            return TaskAttempt(task, None, state, state, "search budget exhausted")
        if found is None:
            return TaskAttempt(task, False, state, state, search.explain())
        after = self._settle(found, running, task, priority)
        return TaskAttempt(task, True, state, after)

    def _settle(
        self, chosen: dict[str, str], running: dict[str, tuple[str, int]], task: str, priority: int
    ) -> TaskState:
        """The new state: the chosen assignment, plus the running tasks that may stay."""
        active = dict(chosen)
        priorities = {t: running[t][1] if t in running else priority for t in chosen}
        priorities[task] = priority
        for other, (behavior, level) in running.items():
            if other in active or self.catalog.exclusive_with(other) & active.keys():
                continue
            active[other] = behavior
            priorities[other] = level
        changed = True
        while changed:  # drop what lost a required task
            changed = False
            for other in list(active):
                entry = self._behavior(other, active[other])
                if entry and any(r.task not in active for r in entry.requires):
                    del active[other]
                    changed = True
        return frozenset((t, b, priorities.get(t, priority)) for t, b in active.items())

    def _behavior(self, task: str, name: str) -> TaskBehavior | None:
        return next((b for b in self.candidates(task) if b.name == name), None)


class _Search:
    def __init__(
        self, model: TaskModel, running: dict[str, tuple[str, int]], priority: int
    ) -> None:
        self.model = model
        self.catalog = model.catalog
        self.running = running
        self.priority = priority
        self.nodes = 0
        self.reasons: list[str] = []

    def note(self, reason: str) -> None:
        if reason not in self.reasons:
            self.reasons.append(reason)

    def explain(self) -> str:
        shown = self.reasons[:3]
        more = len(self.reasons) - len(shown)
        return "; ".join(shown) + (f"; and {more} more" if more > 0 else "") or "no assignment"

    def domain(self, task: str, requested: bool) -> tuple[TaskBehavior, ...]:
        candidates = self.model.candidates(task)
        if task in self.running:
            behavior, level = self.running[task]
            if level > self.priority:
                return tuple(b for b in candidates if b.name == behavior)
            # Keep what runs first: the coordinator changes as little as it can.
            return tuple(sorted(candidates, key=lambda b: b.name != behavior))
        if not requested and self.model.on_request_blocks:
            descriptor = self.catalog.tasks.get(task)
            if descriptor is not None and descriptor.start_on_request:
                self.note(
                    f"{task} starts only on request (start_on_request), not for a requirement"
                )
                return ()
        return tuple(sorted(candidates, key=lambda b: -b.suitability))

    def assign(
        self, task: str, chosen: dict[str, str], requested: bool = False
    ) -> Iterator[dict[str, str]]:
        """Every extension of `chosen` in which `task` is active (depth first)."""
        self.nodes += 1
        if self.nodes > BUDGET:
            raise _OutOfBudget
        if task in chosen:
            yield chosen
            return
        domain = self.domain(task, requested)
        if not domain and not self.model.candidates(task):
            self.note(
                f"no behavior performs {task}"
                if task in self.catalog.tasks
                else f"{task} is not a task of the catalog"
            )
        clash = self.catalog.exclusive_with(task) & chosen.keys()
        if clash and domain:
            self.note(f"{task} and {min(clash)} are mutually exclusive")
            return
        for behavior in domain:
            yield from self._requirements(behavior, 0, {**chosen, task: behavior.name})

    def _requirements(
        self, behavior: TaskBehavior, index: int, chosen: dict[str, str]
    ) -> Iterator[dict[str, str]]:
        if index == len(behavior.requires):
            yield chosen
            return
        requirement = behavior.requires[index]
        for extended in self.assign(requirement.task, chosen):
            performer = self.model._behavior(requirement.task, extended[requirement.task])
            if performer is not None and performer.suitability < requirement.minimum_performance:
                self.note(
                    f"{behavior.name} needs {requirement.task} performed at "
                    f"{requirement.minimum_performance:g} %, {performer.name} gives "
                    f"{performer.suitability:g} %"
                )
                continue
            yield from self._requirements(behavior, index + 1, extended)
