"""AX81x-AX82x: rules over Aerostack 4.x task catalogs (2020-2021).

What the 2021 coordinator (cvar-upm/coordinator_cbc) rejects when it loads a catalog —
'The required task: X is not declared', 'Conflicting constraints', start_on_request
with reactive_start, a requirement cycle on which its task ordering never ends — and
what makes a `start_task` impossible later: a task nobody performs, a requirement no
behavior can meet, mutually exclusive requirements, a requirement on a task that only
starts on request. Rules with witnesses give the shortest `start_task` sequence that
shows the problem on `aeroexec.verifier.task_model`.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from functools import cached_property
from typing import TYPE_CHECKING

from aeroexec.catalog.model import Severity
from aeroexec.catalog.tasks import ExecutionGoal, TaskBehavior, TaskCatalog
from aeroexec.errors import Mark
from aeroexec.verifier.cycles import cyclic_components, shortest_cycle
from aeroexec.verifier.findings import Finding, Outcome, Step, Witness
from aeroexec.verifier.registry import task_rule
from aeroexec.verifier.suggest import Suggester
from aeroexec.verifier.task_model import IDLE, TaskModel

if TYPE_CHECKING:
    import networkx as nx

E, W, INFO = Severity.ERROR, Severity.WARNING, Severity.INFO


class TaskContext:
    """What every task rule receives: the catalog, its indexes and the model."""

    def __init__(self, catalog: TaskCatalog) -> None:
        self.catalog = catalog
        self.file = catalog.source

    def finding(
        self,
        rule: str,
        severity: Severity,
        message: str,
        mark: Mark,
        subjects: Iterable[str] = (),
        witness: Witness | None = None,
    ) -> Finding:
        return Finding.in_file(self.file, rule, severity, message, mark, subjects, witness)

    @cached_property
    def known_tasks(self) -> Suggester:
        return Suggester(self.catalog.tasks)

    @cached_property
    def strict(self) -> TaskModel:
        """The coordinator: requirements do not start `start_on_request` tasks."""
        return TaskModel(self.catalog)

    @cached_property
    def permissive(self) -> TaskModel:
        """As if every task could be started for a requirement (or had been requested)."""
        return TaskModel(self.catalog, on_request_blocks=False)

    def performed(self, task: str) -> bool:
        return bool(self.catalog.performers(task))

    def task_mark(self, task: str) -> Mark:
        descriptor = self.catalog.tasks.get(task)
        return descriptor.mark if descriptor is not None else Mark(self.file)

    def rejected(self, task: str, model: TaskModel | None = None) -> Witness | None:
        """[start_task task] from an idle coordinator, when the model rejects it."""
        attempt = (model or self.strict).start_task(IDLE, task)
        if attempt.accepted is False:
            return Witness((Step(task, service="start_task"),), Outcome.REJECTED)
        return None

    def requirements(self) -> Iterator[tuple[TaskBehavior, int]]:
        for behavior in self.catalog.behaviors:
            for index in range(len(behavior.requires)):
                yield behavior, index

    @cached_property
    def requirement_graph(self) -> nx.DiGraph:
        """Task -> task it needs (through any behavior performing it); each edge keeps
        the first requirement that imposes it (edge attribute `requirement`)."""
        import networkx as nx

        graph = nx.DiGraph()
        for behavior in self.catalog.behaviors:
            if behavior.task is None:
                continue
            graph.add_node(behavior.task)
            for requirement in behavior.requires:
                if not graph.has_edge(behavior.task, requirement.task):
                    graph.add_edge(behavior.task, requirement.task, requirement=requirement)
        return graph


def _constraint(behavior: TaskBehavior, required: str, minimum: float) -> str:
    """The coordinator's own notation, as its error message prints it."""
    return f"requires({behavior.name}({behavior.task}),{required},{minimum / 100:.6f})"


@task_rule(
    "AX811",
    "task-without-behavior",
    W,
    """A task declared in `tasks` that no behavior performs (the Pixhawk catalog of
    2021 declares HOVER, MOVE_AT_SPEED and two control tasks whose behaviors were
    commented out; the CBC's bad_behavior_catalog.yaml declares LAND after its behavior
    lost its task). The coordinator drops such tasks when it loads the catalog. In
    flight: `start_task` of it is refused ('No possible activations found'), a
    `reactive_start` one never starts, and behaviors requiring it can never run. Fix:
    add a behavior that performs it, or remove the declaration.""",
    witness=True,
)
def task_without_behavior(ctx: TaskContext) -> Iterator[Finding]:
    for task, descriptor in ctx.catalog.tasks.items():
        if not descriptor.declared or ctx.performed(task):
            continue
        extra = ", so its reactive start never happens" if descriptor.reactive_start else ""
        users = sorted(
            {b.name for b in ctx.catalog.behaviors for r in b.requires if r.task == task}
        )
        if users:
            extra += f"; behaviors requiring it can never run: {', '.join(users)}"
        yield ctx.finding(
            "AX811",
            W,
            f"no behavior performs task {task}: start_task({task}) is refused{extra}",
            descriptor.mark,
            (task, *users),
            ctx.rejected(task),
        )


@task_rule(
    "AX812",
    "undefined-required-task",
    E,
    """A behavior requires a task that is neither declared in `tasks` nor performed by
    any behavior (the CBC's behavior_catalog_missing_task.yaml:
    SELF_LOCALIZE_NON_EXISTENT). The coordinator reports 'The required task: X is not
    declared' when it loads the catalog. In flight: the requiring behavior can never be
    chosen, so its task falls to other behaviors or cannot start at all. Fix: correct the
    name (the message suggests the closest task) or add the task.""",
)
def undefined_required_task(ctx: TaskContext) -> Iterator[Finding]:
    for behavior, index in ctx.requirements():
        requirement = behavior.requires[index]
        if requirement.task in ctx.catalog.tasks:
            continue
        yield ctx.finding(
            "AX812",
            E,
            f"{behavior.name} requires task {requirement.task}, which is not declared (the "
            f"coordinator: 'The required task: {requirement.task} is not declared')"
            f"{ctx.known_tasks.hint(requirement.task)}: {behavior.name} can never run",
            requirement.mark,
            (behavior.name, requirement.task),
        )


@task_rule(
    "AX813",
    "unperformed-required-task",
    E,
    """A behavior requires a task that is declared but that no behavior performs. In
    flight: the requirement can never be met, so the behavior is never chosen. Fix: add
    a behavior performing the required task, or drop the requirement.""",
    witness=True,
)
def unperformed_required_task(ctx: TaskContext) -> Iterator[Finding]:
    for behavior, index in ctx.requirements():
        requirement = behavior.requires[index]
        if requirement.task not in ctx.catalog.tasks or ctx.performed(requirement.task):
            continue
        witness = None
        if behavior.task is not None and len(ctx.catalog.performers(behavior.task)) == 1:
            witness = ctx.rejected(behavior.task, ctx.permissive)
        yield ctx.finding(
            "AX813",
            E,
            f"{behavior.name} requires task {requirement.task}, which no behavior performs: "
            f"{behavior.name} can never run",
            requirement.mark,
            (behavior.name, requirement.task),
            witness,
        )


@task_rule(
    "AX814",
    "conflicting-constraints",
    E,
    """A behavior requires a task that is mutually exclusive with the task the behavior
    performs (the CBC's behavior_catalog_impossible.yaml: QUADROTOR_PID_MOTION_CONTROL
    performs PID_MOTION_CONTROL and requires MPC_MOTION_CONTROL, which is mutually
    exclusive with it). The coordinator reports 'Conflicting constraints' when it loads
    the catalog. In flight: the behavior can never run. Fix: drop the requirement or the
    exclusivity.""",
    witness=True,
)
def conflicting_constraints(ctx: TaskContext) -> Iterator[Finding]:
    for behavior, index in ctx.requirements():
        requirement = behavior.requires[index]
        task = behavior.task
        if task is None or requirement.task not in ctx.catalog.exclusive_with(task):
            continue
        witness = None
        if len(ctx.catalog.performers(task)) == 1:
            witness = ctx.rejected(task, ctx.permissive)
        yield ctx.finding(
            "AX814",
            E,
            f"{behavior.name} performs {task} and requires {requirement.task}, but the two "
            "tasks are mutually exclusive (the coordinator: 'Conflicting constraints: "
            f"{_constraint(behavior, requirement.task, requirement.minimum_performance)} "
            f"and incompatible({task},{requirement.task})'): {behavior.name} can never run",
            requirement.mark,
            (behavior.name, task, requirement.task),
            witness,
        )


@task_rule(
    "AX815",
    "exclusive-requirements",
    E,
    """A behavior requires two tasks that are mutually exclusive with each other (the
    CBC's behavior_catalog_impossible.yaml: QUADROTOR_PID_MOTION_CONTROL requires
    THRUST_CONTROL and MPC_MOTION_CONTROL). Both must run while the behavior runs, and
    they never run together. In flight: the behavior can never be chosen. Fix: drop one
    requirement or the exclusivity.""",
)
def exclusive_requirements(ctx: TaskContext) -> Iterator[Finding]:
    for behavior in ctx.catalog.behaviors:
        seen: list[str] = []
        for requirement in behavior.requires:
            clash = [t for t in seen if t in ctx.catalog.exclusive_with(requirement.task)]
            if clash:
                yield ctx.finding(
                    "AX815",
                    E,
                    f"{behavior.name} requires {clash[0]} and {requirement.task}, which are "
                    f"mutually exclusive: {behavior.name} can never run",
                    requirement.mark,
                    (behavior.name, clash[0], requirement.task),
                )
            seen.append(requirement.task)


@task_rule(
    "AX816",
    "task-never-starts",
    E,
    """A task some behavior performs, but that no `start_task` can ever start: every
    behavior performing it fails a requirement (transitively), whatever was started
    before. Usually the consequence of another finding (in the CBC's
    behavior_catalog_impossible.yaml, MOVE is performed only by a behavior that needs
    PID_MOTION_CONTROL, which can never run); this one names the task a mission would
    ask for. In flight: start_task of it is refused. Fix: repair the requirement the
    message names.""",
    witness=True,
)
def task_never_starts(ctx: TaskContext) -> Iterator[Finding]:
    for task in ctx.catalog.tasks:
        if not ctx.performed(task):
            continue
        attempt = ctx.permissive.start_task(IDLE, task)
        if attempt.accepted is not False:
            continue
        performers = ", ".join(dict.fromkeys(ctx.catalog.performers(task)))
        yield ctx.finding(
            "AX816",
            E,
            f"task {task} can never start: none of its behaviors ({performers}) can run "
            f"({attempt.reason})",
            ctx.task_mark(task),
            (task, *dict.fromkeys(ctx.catalog.performers(task))),
            Witness((Step(task, service="start_task"),), Outcome.REJECTED),
        )


@task_rule(
    "AX817",
    "reactive-start-on-request",
    E,
    """A task is both `start_on_request: TRUE` and `reactive_start: TRUE` (defaults
    included). The coordinator reports 'incompatible fields start_on_request: TRUE and
    reactive_start: TRUE' when it loads the catalog. In flight: a task that may only be
    started by request cannot also start by itself. Checked on catalogs that use the 2021
    vocabulary (a 2020 `default: TRUE` with `automatic_activation: FALSE` is how those
    catalogs wrote a default task). Fix: set `start_on_request: FALSE` for a task that
    starts reactively.""",
)
def reactive_start_on_request(ctx: TaskContext) -> Iterator[Finding]:
    if ctx.catalog.dialect == "aerostack-4.0-2020":
        return  # the pair is the 2021 coordinator's rule; 2020 catalogs say it otherwise
    for task, descriptor in ctx.catalog.tasks.items():
        if descriptor.declared and descriptor.start_on_request and descriptor.reactive_start:
            yield ctx.finding(
                "AX817",
                E,
                f"task {task} has start_on_request: TRUE and reactive_start: TRUE (the "
                "coordinator refuses this pair: reactive_start: FALSE is required)",
                descriptor.mark_of("reactive_start"),
                (task,),
            )


@task_rule(
    "AX818",
    "requirement-on-request-only",
    W,
    """A behavior requires a task that starts only on request (`start_on_request:
    TRUE`, the default) and not reactively. The coordinator never starts such a task to
    meet a requirement: it stays inactive unless a mission asked for it (the Pixhawk
    catalog's SEND_PATH requires FOLLOW_PATH, declared with the defaults). In flight:
    the requiring behavior can only run after the required task was started by request,
    and stops being possible when that task ends. Fix: declare the required task
    `start_on_request: FALSE`, or start it from the mission first.""",
    witness=True,
)
def requirement_on_request_only(ctx: TaskContext) -> Iterator[Finding]:
    for behavior, index in ctx.requirements():
        requirement = behavior.requires[index]
        descriptor = ctx.catalog.tasks.get(requirement.task)
        if descriptor is None or not ctx.performed(requirement.task):
            continue
        if not descriptor.start_on_request or descriptor.reactive_start:
            continue
        witness = None
        if behavior.task is not None and ctx.permissive.start_task(IDLE, behavior.task).accepted:
            witness = ctx.rejected(behavior.task)
        default = "" if descriptor.wrote("start_on_request") else " (by default)"
        yield ctx.finding(
            "AX818",
            W,
            f"{behavior.name} requires {requirement.task}, which starts only on request"
            f"{default}: the coordinator does not start it for the requirement, so "
            f"{behavior.name} runs only while {requirement.task} was started by request",
            requirement.mark,
            (behavior.name, requirement.task),
            witness,
        )


@task_rule(
    "AX819",
    "requirement-cycle",
    E,
    """Tasks that require each other in a cycle (a behavior of A requires B, a behavior
    of B requires A, or a behavior requires its own task). The coordinator orders tasks
    so that required ones come first (`ordenateTasks`); on a cycle that loop never ends.
    In flight: the coordinator hangs at the first `start_task`, when it loads the
    catalog. Fix: break the cycle.""",
)
def requirement_cycle(ctx: TaskContext) -> Iterator[Finding]:
    graph = ctx.requirement_graph
    order = {name: i for i, name in enumerate(ctx.catalog.tasks)}
    components = cyclic_components(graph)
    components.sort(key=lambda c: min(order.get(t, len(order)) for t in c))
    for component in components:
        cycle = shortest_cycle(graph, component, lambda t: order.get(t, len(order)))
        first = graph.edges[cycle[0], cycle[1]]["requirement"]
        yield ctx.finding(
            "AX819",
            E,
            f"tasks require each other in a cycle: {' -> '.join(cycle)}; the coordinator's "
            "task ordering never ends on it (it hangs loading the catalog)",
            first.mark,
            sorted(component, key=lambda t: order.get(t, len(order))),
        )


@task_rule(
    "AX820",
    "unreachable-minimum-performance",
    E,
    """A requirement's `minimum_performance` is higher than the suitability of every
    behavior that performs the required task. In flight: the requirement can never be
    met, so the requiring behavior is never chosen. Fix: lower the minimum, or raise the
    suitability of a behavior that deserves it.""",
)
def unreachable_minimum_performance(ctx: TaskContext) -> Iterator[Finding]:
    model = ctx.strict
    for behavior, index in ctx.requirements():
        requirement = behavior.requires[index]
        performers = model.candidates(requirement.task)
        if not performers or requirement.minimum_performance <= 0:
            continue
        best = max(performers, key=lambda b: b.suitability)
        if best.suitability < requirement.minimum_performance:
            yield ctx.finding(
                "AX820",
                E,
                f"{behavior.name} needs {requirement.task} performed at "
                f"{requirement.minimum_performance:g} %, but its best behavior {best.name} "
                f"has a suitability of {best.suitability:g} %: {behavior.name} can never run",
                requirement.mark,
                (behavior.name, requirement.task, best.name),
            )


@task_rule(
    "AX821",
    "undefined-exclusive-task",
    W,
    """An exclusivity constraint names a task that is neither declared nor performed.
    The coordinator skips names it does not know. In flight: the exclusivity meant is not
    enforced (often a misspelt task, which then runs together with the others). Fix:
    correct the name (the message suggests the closest task) or remove it.""",
)
def undefined_exclusive_task(ctx: TaskContext) -> Iterator[Finding]:
    for constraint in ctx.catalog.exclusions:
        for index, task in enumerate(constraint.tasks):
            if task not in ctx.catalog.tasks:
                yield ctx.finding(
                    "AX821",
                    W,
                    f"mutually_exclusive names {task}, which is not a task"
                    f"{ctx.known_tasks.hint(task)}: the coordinator ignores it",
                    constraint.mark_of(f"tasks.{index}"),
                    (task,),
                )


@task_rule(
    "AX822",
    "ineffective-exclusion",
    W,
    """An exclusivity constraint with fewer than two distinct tasks, or that names a task
    twice. In flight: a constraint with one task excludes nothing; a repeated name
    usually hides a task that was meant. Fix: complete the constraint or remove it.""",
)
def ineffective_exclusion(ctx: TaskContext) -> Iterator[Finding]:
    for constraint in ctx.catalog.exclusions:
        seen: set[str] = set()
        for index, task in enumerate(constraint.tasks):
            if task in seen:
                yield ctx.finding(
                    "AX822",
                    W,
                    f"mutually_exclusive names {task} twice",
                    constraint.mark_of(f"tasks.{index}"),
                    (task,),
                )
            seen.add(task)
        if len(seen) < 2:
            yield ctx.finding(
                "AX822",
                W,
                "an exclusivity constraint with fewer than two tasks excludes nothing",
                constraint.mark,
                tuple(seen) or ("mutually_exclusive",),
            )


@task_rule(
    "AX823",
    "undeclared-task",
    INFO,
    """A behavior performs a task that `tasks` does not declare. In flight: the
    coordinator gives it its own defaults — started only on request, not reactively,
    achieve-goal with the default timeout — whatever `default_values` says. Fix: declare
    the task if it needs other attributes.""",
)
def undeclared_task(ctx: TaskContext) -> Iterator[Finding]:
    for task, descriptor in ctx.catalog.tasks.items():
        if descriptor.declared:
            continue
        performers = ", ".join(dict.fromkeys(ctx.catalog.performers(task)))
        yield ctx.finding(
            "AX823",
            INFO,
            f"task {task} (performed by {performers}) is not declared in tasks: it starts "
            f"only on request and times out after {descriptor.timeout:g} s",
            descriptor.mark,
            (task,),
        )


@task_rule(
    "AX824",
    "timeout-on-keep-running",
    W,
    """A `keep_running` (2020: `recurrent`) task is given a `timeout`. The coordinator
    arms timeouts only for tasks that achieve a goal. In flight: the task never times
    out, whatever the value says. Fix: remove the timeout, or make the task
    achieve_goal if it should end.""",
)
def timeout_on_keep_running(ctx: TaskContext) -> Iterator[Finding]:
    for task, descriptor in ctx.catalog.tasks.items():
        if descriptor.execution_goal is ExecutionGoal.KEEP_RUNNING and descriptor.wrote("timeout"):
            yield ctx.finding(
                "AX824",
                W,
                f"task {task} keeps running, so its timeout of {descriptor.timeout:g} s is "
                "never armed",
                descriptor.mark_of("timeout"),
                (task,),
            )
