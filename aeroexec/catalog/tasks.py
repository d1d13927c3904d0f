"""The Aerostack 4.x task catalog (2020-2021): behaviors perform tasks.

A different model from the 2017 behavior catalog, not a variant of it: a mission asks
for a *task* (`start_task(TAKE_OFF)`); the coordinator chooses which *behavior* performs
it (the most suitable one whose requirements can be met), starts the tasks that
behavior *requires*, and keeps *mutually exclusive* tasks from running together. There
are no behavior lists, capabilities or processes.

Two vocabularies for the same attributes were in use (see `aeroexec.catalog.task_loader`):
2020 (Aerostack 4.0's behavior manager): `category`, `default`, `automatic_activation`,
`efficacy`; 2021 (the CBC coordinator, cvar-upm/coordinator_cbc): `execution_goal`,
`reactive_start`, `start_on_request`, `suitability`. The model holds the meaning.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import Enum

from aeroexec.catalog.model import IN_MEMORY, Diagnostic, Severity
from aeroexec.errors import Mark

#: The CBC's own default when a catalog's `default_values` gives no timeout (seconds).
DEFAULT_TASK_TIMEOUT_S = 15
DEFAULT_SUITABILITY = 100.0


class ExecutionGoal(str, Enum):
    ACHIEVE_GOAL = "achieve_goal"  # ends by itself; the coordinator arms the timeout
    KEEP_RUNNING = "keep_running"  # runs until stopped; no timeout


class ParameterKind(str, Enum):
    RANGE = "range"  # numbers in [minimum, maximum]
    SYMBOLS = "symbols"  # one of a list of words
    TYPE = "type"  # a type word: string, point, point_list, list_of_strings...
    UNSPECIFIED = "unspecified"  # no allowed_values
    INVALID = "invalid"  # malformed: the loader reported it


@dataclass(frozen=True, slots=True)
class ParameterSpec:
    name: str
    kind: ParameterKind
    minimum: float | None = None
    maximum: float | None = None
    symbols: tuple[str, ...] = ()
    type_name: str = ""
    mark: Mark = IN_MEMORY


@dataclass(frozen=True, slots=True)
class TaskDescriptor:
    """A task as the coordinator sees it: declared in `tasks`, or only performed by a
    behavior (`declared` False: the coordinator then gives it its own defaults)."""

    name: str
    execution_goal: ExecutionGoal
    start_on_request: bool
    reactive_start: bool
    timeout: float
    parameters: tuple[ParameterSpec, ...] = ()
    declared: bool = True
    mark: Mark = IN_MEMORY
    #: Marks of written attributes ("timeout", "start_on_request", ...).
    marks: Mapping[str, Mark] = field(default_factory=dict, compare=False, hash=False)

    def mark_of(self, key: str) -> Mark:
        return self.marks.get(key, self.mark)

    def wrote(self, key: str) -> bool:
        return key in self.marks


@dataclass(frozen=True, slots=True)
class Requirement:
    """`requires: - task: T, minimum_performance: P` of one behavior."""

    task: str
    minimum_performance: float = 0.0  # percent
    mark: Mark = IN_MEMORY


@dataclass(frozen=True, slots=True)
class TaskBehavior:
    name: str
    task: str | None  # None: the entry names no task (a loader error)
    suitability: float = DEFAULT_SUITABILITY  # percent
    package: str = ""
    requires: tuple[Requirement, ...] = ()
    mark: Mark = IN_MEMORY
    marks: Mapping[str, Mark] = field(default_factory=dict, compare=False, hash=False)

    def mark_of(self, key: str) -> Mark:
        return self.marks.get(key, self.mark)


@dataclass(frozen=True, slots=True)
class ExclusionConstraint:
    """`- mutually_exclusive: [A, B, ...]`: no two of them run at the same time."""

    tasks: tuple[str, ...]
    mark: Mark = IN_MEMORY
    #: "tasks.i" -> where the i-th task is named.
    marks: Mapping[str, Mark] = field(default_factory=dict, compare=False, hash=False)

    def mark_of(self, key: str) -> Mark:
        return self.marks.get(key, self.mark)


@dataclass(frozen=True, slots=True)
class TaskDefaults:
    execution_goal: ExecutionGoal = ExecutionGoal.ACHIEVE_GOAL
    start_on_request: bool = True
    reactive_start: bool = False
    timeout: float = DEFAULT_TASK_TIMEOUT_S
    suitability: float = DEFAULT_SUITABILITY


@dataclass(frozen=True, eq=False)
class TaskCatalog:
    """A loaded task catalog. `behaviors` keeps every entry in file order (the
    coordinator keeps a list, so a repeated name is two candidates); `tasks` holds the
    effective task of each name (a later declaration replaces an earlier one)."""

    behaviors: tuple[TaskBehavior, ...]
    tasks: Mapping[str, TaskDescriptor]
    exclusions: tuple[ExclusionConstraint, ...] = ()
    defaults: TaskDefaults = field(default_factory=TaskDefaults)
    #: Every entry of `tasks:` in file order, repeated names included.
    declarations: tuple[TaskDescriptor, ...] = ()
    source: str = "<memory>"
    dialect: str = "cbc-2021"
    text: str = ""
    diagnostics: tuple[Diagnostic, ...] = ()
    section_marks: Mapping[str, Mark] = field(default_factory=dict)

    _performers: dict[str, tuple[str, ...]] = field(init=False, repr=False)
    _exclusive: dict[str, frozenset[str]] = field(init=False, repr=False)
    _by_name: dict[str, TaskBehavior] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        performers: dict[str, list[str]] = {}
        by_name: dict[str, TaskBehavior] = {}
        for behavior in self.behaviors:
            by_name.setdefault(behavior.name, behavior)
            if behavior.task is not None:
                performers.setdefault(behavior.task, []).append(behavior.name)
        exclusive: dict[str, set[str]] = {}
        for constraint in self.exclusions:
            members = set(constraint.tasks)
            for task in members:
                exclusive.setdefault(task, set()).update(members - {task})
        object.__setattr__(self, "_performers", {k: tuple(v) for k, v in performers.items()})
        object.__setattr__(self, "_exclusive", {k: frozenset(v) for k, v in exclusive.items()})
        object.__setattr__(self, "_by_name", by_name)

    def performers(self, task: str) -> tuple[str, ...]:
        """Behaviors (file order, by name) that perform `task`."""
        return self._performers.get(task, ())

    def exclusive_with(self, task: str) -> frozenset[str]:
        """Tasks that may not run while `task` runs (symmetric)."""
        return self._exclusive.get(task, frozenset())

    def behavior(self, name: str) -> TaskBehavior | None:
        """The first behavior entry of that name."""
        return self._by_name.get(name)

    def task(self, name: str) -> TaskDescriptor | None:
        return self.tasks.get(name)

    def warnings(self) -> tuple[Diagnostic, ...]:
        return tuple(d for d in self.diagnostics if d.severity is not Severity.ERROR)
