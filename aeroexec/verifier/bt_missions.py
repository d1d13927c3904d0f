"""Aerostack's behavior-tree missions (YAML `nodes:`), checked against a task catalog.

Aerostack 4.x's behavior-tree editor saves a mission as a list of nodes, each with its
`parent` (0 for the root): `control_flow` nodes (`sequence`, `fallback`/`selector`,
`parallel`...) and `execution` nodes that start a task (`subtype: task`, `task: ROTATE`,
`parameters: "angle: 90"`, `wait_for_completion: true|false`). The file is read as data,
never run. Each execution node is checked as a mission call is:

* AX701 the task exists in the catalog, and some behavior performs it;
* AX702 each parameter is one the task declares;
* AX703 a value fits the declared range, words or type; AX704 a point has 3 numbers.

Then the tree is run on the same model of the 2021 task coordinator the task rules and
witnesses use (`task_model.TaskModel`), with the control nodes of Aerostack's
behavior-tree interpreter (`_TreeRun`): each node succeeds or fails; a sequence runs its
children in order while they succeed, a fallback while they fail (the next child from
the state the failed one left), a parallel starts its children's tasks together, and
inverter, succeeder, repeater and repeat-until-fail change or repeat what their child
gives. A task waited for (`wait_for_completion: true`) ends before the next node (an
`achieve_goal` task reaches its goal; any may fail); one not waited for keeps running.
The sequence checks:

* AX716 a task started without waiting for it is stopped by a later node's task (a
  mutually exclusive one) before it could end;
* AX717 the coordinator rejects a node's `start_task` in the state the tree leaves, and
  no fallback, inverter or succeeder above it takes the failure: the mission fails.

Against a behavior catalog (the 2017/2.x generation, whose behaviors the executive
runs), the tree becomes the flow a Python mission folds to (`as_folded`): a node
waited for is `execute_behavior`, one not waited for `activate_behavior`, a sequence
runs in order and any other control node is a branch of its children. It is then
checked exactly as a Python mission is, call by call and by the abstract run in the
executive (AX701-AX715).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from aeroexec.catalog.model import Severity
from aeroexec.catalog.tasks import ExecutionGoal, ParameterKind, ParameterSpec, TaskCatalog
from aeroexec.catalog.yamlnodes import YNode, load_yaml
from aeroexec.errors import AeroexecError, CatalogError, Mark, MissionError
from aeroexec.inputs import read_text
from aeroexec.verifier.findings import Finding, PathStep
from aeroexec.verifier.mission_fold import (
    Branch,
    CallArgument,
    CallNode,
    Flow,
    FoldedMission,
    MissionCall,
)
from aeroexec.verifier.missions import (
    BAD_VALUE,
    UNKNOWN_ARGUMENT,
    UNKNOWN_BEHAVIOR,
    WRONG_DIMENSIONS,
    MissionScript,
)
from aeroexec.verifier.registry import mission_rule
from aeroexec.verifier.suggest import Suggester
from aeroexec.verifier.task_model import IDLE, TaskModel, TaskState

E, W = Severity.ERROR, Severity.WARNING

TASK_INTERRUPTED = mission_rule(
    "AX716",
    "bt-task-interrupted",
    W,
    """In a behavior-tree mission, a node starts a task without waiting for it
    (`wait_for_completion: false`, or any task child of a `parallel` node, whose
    children start together) and a later node starts a task that is mutually exclusive
    with it: the coordinator stops the first task at once. In
    flight: the first task hardly runs (a TAKE_OFF stopped by the next motion task
    leaves the vehicle on the ground). Fix: set `wait_for_completion: true` on the first
    node; tasks that must overlap cannot be mutually exclusive. The mission is read as
    written: Aerostack's 2021 interpreter parses `wait_for_completion` but waits for
    every task anyway, so a flight on it does not show the stop; the warning says the
    mission depends on that, and that its words ask for the stop.""",
).code
TASK_REJECTED = mission_rule(
    "AX717",
    "bt-task-rejected",
    E,
    """In a behavior-tree mission, the 2021 task coordinator (as the task rules model
    it) rejects a node's `start_task` in the state the nodes before it leave: no
    assignment of behaviors satisfies the catalog's exclusivity constraints and
    requirements. Not reported when a fallback above the node tries another child
    then (or an inverter or succeeder takes the failure): that is what they are for.
    In flight: the node fails, its sequence with it, and the mission ends there. Fix:
    stop the conflicting task first, or change the catalog's constraints.""",
).code

_TYPE_DIMENSIONS = {"point": 3}


@dataclass(frozen=True, slots=True)
class BtNode:
    number: int
    name: str
    kind: str  # "control_flow" | "execution" | ...
    subtype: str
    task: str | None
    parameters: dict[str, Any] | None  # None: no parameters, or unreadable ones
    wait: bool
    parent: int
    mark: Mark
    task_mark: Mark
    parameters_mark: Mark
    #: The `parameters` text when it cannot be read as `name: value` pairs.
    unreadable: str | None = None
    children: list[BtNode] = field(default_factory=list, compare=False)

    @property
    def shown(self) -> str:
        return f"node {self.number} ({self.name})" if self.name else f"node {self.number}"


@dataclass(frozen=True)
class BtMission:
    path: str
    roots: tuple[BtNode, ...]
    nodes: tuple[BtNode, ...]


def is_bt_mission(root: YNode | None) -> bool:
    """A YAML document holding a behavior tree (`nodes:`) rather than a catalog."""
    return (
        root is not None
        and root.is_map
        and root.get("nodes") is not None
        and not any(root.get(k) is not None for k in ("behavior_descriptors", "behaviors", "tasks"))
    )


def read_bt_mission(path: str) -> BtMission:
    text = read_text(path, "a behavior-tree mission", MissionError)
    try:
        root = load_yaml(text, path)
    except CatalogError as exc:
        raise MissionError(exc.message, exc.mark) from None
    return parse_bt_mission(root, path)


def parse_bt_mission(root: YNode | None, path: str) -> BtMission:
    if not is_bt_mission(root):
        raise MissionError("not a behavior-tree mission (no 'nodes' list)", Mark(path, 1, 1))
    assert root is not None
    listed = root.get("nodes")
    assert listed is not None
    if not listed.is_list:
        raise MissionError("'nodes' must be a list of nodes", listed.mark)
    nodes: dict[int, BtNode] = {}
    for entry in listed.value:
        node = _node(entry)
        if node.number in nodes:
            raise MissionError(f"node {node.number} is defined twice", entry.mark)
        nodes[node.number] = node
    roots: list[BtNode] = []
    for node in nodes.values():
        if node.parent == 0:
            roots.append(node)
        elif node.parent in nodes and node.parent != node.number:
            nodes[node.parent].children.append(node)
        else:
            raise MissionError(f"{node.shown}: no parent node {node.parent}", node.mark)
    _refuse_cycles(nodes)
    return BtMission(path, tuple(roots), tuple(nodes.values()))


def _node(entry: YNode) -> BtNode:
    if not entry.is_map:
        raise MissionError("a node must be a mapping (node, name, type, parent...)", entry.mark)

    def integer(key: str) -> int:
        value = entry.get(key)
        if value is None or not isinstance(value.value, int) or isinstance(value.value, bool):
            raise MissionError(f"a node needs '{key}' (an integer)", entry.mark)
        return value.value

    def text(key: str) -> str:
        value = entry.get(key)
        return str(value.text) if value is not None and value.value is not None else ""

    parameters: dict[str, Any] | None = None
    unreadable: str | None = None
    given = entry.get("parameters")
    if given is not None and given.value is not None:
        parameters = _parameters(given)
        if parameters is None:
            unreadable = str(given.text)
    waiting = entry.get("wait_for_completion")
    wait = bool(waiting.value) if waiting is not None and isinstance(waiting.value, bool) else True
    task = entry.get("task") or entry.get("behavior")
    return BtNode(
        integer("node"),
        text("name"),
        text("type"),
        text("subtype"),
        str(task.text) if task is not None and task.value is not None else None,
        parameters,
        wait,
        integer("parent"),
        entry.mark,
        task.mark if task is not None else entry.mark,
        given.mark if given is not None else entry.mark,
        unreadable,
    )


def _parameters(given: YNode) -> dict[str, Any] | None:
    """`parameters: "angle: 90, speed: 1"` (YAML text, as the editor writes it) or a
    mapping; None when it cannot be read as one."""
    if given.is_map:
        return given.plain()  # type: ignore[no-any-return]
    if not isinstance(given.value, str):
        return None
    for text in (given.value, "{" + given.value + "}"):
        try:
            parsed = load_yaml(text, given.mark.file)
        except AeroexecError:
            continue
        if parsed is not None and parsed.is_map:
            return parsed.plain()  # type: ignore[no-any-return]
    return None


#: Levels of a tree the checks follow (they recurse); Aerostack's trees have a handful.
MAX_TREE_DEPTH = 200


def _refuse_cycles(nodes: dict[int, BtNode]) -> None:
    """A `MissionError` for parents that form a cycle or a tree deeper than
    MAX_TREE_DEPTH; each node is walked once (depths are remembered)."""
    depth: dict[int, int] = {0: 0}
    for node in nodes.values():
        path: list[int] = []
        on_path: set[int] = set()
        current = node.number
        while current not in depth:
            if current in on_path:
                raise MissionError(f"{node.shown}: its parents form a cycle", node.mark)
            on_path.add(current)
            path.append(current)
            current = nodes[current].parent if current in nodes else 0
        level = depth[current]
        for number in reversed(path):
            level += 1
            depth[number] = level
            if level > MAX_TREE_DEPTH:
                raise MissionError(
                    f"{nodes[number].shown}: the tree is nested deeper than "
                    f"{MAX_TREE_DEPTH} levels",
                    nodes[number].mark,
                )


# -- as a Python mission folds (behavior catalogs) --------------------------------------------
def as_folded(mission: BtMission) -> MissionScript:
    """The tree as the flow of mission calls a Python mission folds to."""
    calls: list[MissionCall] = []

    def flow_of(node: BtNode) -> Flow:
        if node.kind == "execution":
            if node.task is None:
                return ()
            kind = "execute" if node.wait else "activate"
            arguments = tuple(
                CallArgument(str(name), _as_argument(value), node.parameters_mark)
                for name, value in (node.parameters or {}).items()
            )
            call = MissionCall(
                kind,
                f"{kind}_behavior",
                node.task,
                arguments,
                (),
                node.task_mark,
                node.task_mark,
            )
            calls.append(call)
            return (CallNode(call),)
        parts = [flow_of(child) for child in node.children]
        if node.subtype in ("sequence", "parallel", "") or len(parts) <= 1:
            return tuple(n for part in parts for n in part)
        arms = tuple(
            (f"node {c.number}", part) for c, part in zip(node.children, parts, strict=True)
        )
        return (Branch(node.mark, arms),)

    flow = tuple(n for root in mission.roots for n in flow_of(root))
    return MissionScript(mission.path, FoldedMission(flow, "behavior tree", tuple(calls)))


def _as_argument(value: Any) -> Any:
    if isinstance(value, list):
        return [_as_argument(v) for v in value]
    return value if isinstance(value, (str, int, float, bool)) or value is None else str(value)


# -- checking ---------------------------------------------------------------------------
def check_bt_mission(mission: BtMission, catalog: TaskCatalog, note: str = "") -> list[Finding]:
    findings: list[Finding] = []
    names = Suggester(list(catalog.tasks))
    for node in mission.nodes:
        if node.kind == "execution" and node.task is not None:
            findings.extend(_check_node(node, catalog, names, note))
    findings.extend(_TreeRun(catalog, note).run(mission))
    return list(dict.fromkeys(findings))


def _check_node(
    node: BtNode, catalog: TaskCatalog, names: Suggester, note: str
) -> Iterator[Finding]:
    task = node.task
    assert task is not None
    descriptor = catalog.tasks.get(task)
    if descriptor is None or not catalog.performers(task):
        why = (
            f"unknown task {task}{names.hint(task)}"
            if descriptor is None
            else f"no behavior of the catalog performs {task}"
        )
        yield Finding.at(UNKNOWN_BEHAVIOR, E, f"{node.shown}: {why}{note}", node.task_mark, (task,))
        return
    if node.unreadable is not None:
        yield Finding.at(
            UNKNOWN_ARGUMENT,
            E,
            f"{node.shown}: the parameters of {task} cannot be read as 'name: value' pairs: "
            f"{node.unreadable!r}{note}",
            node.parameters_mark,
            (task,),
        )
    declared = {spec.name.casefold(): spec for spec in descriptor.parameters}
    for name, value in (node.parameters or {}).items():
        spec = declared.get(str(name).casefold())
        if spec is None:
            listed = ", ".join(s.name for s in descriptor.parameters) or "none"
            hint = Suggester([s.name for s in descriptor.parameters]).hint(str(name))
            yield Finding.at(
                UNKNOWN_ARGUMENT,
                E,
                f"{node.shown}: {task} has no parameter '{name}'{hint} (parameters: "
                f"{listed}){note}",
                node.parameters_mark,
                (task, str(name)),
            )
            continue
        problem = _value_problem(spec, value)
        if problem is not None:
            rule, text = problem
            yield Finding.at(
                rule,
                E,
                f"{node.shown}: {task} parameter {spec.name} {text}{note}",
                node.parameters_mark,
                (task, spec.name),
            )


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _point(value: Any) -> bool:
    return isinstance(value, list) and len(value) == 3 and all(_number(v) for v in value)


def _value_problem(spec: ParameterSpec, value: Any) -> tuple[str, str] | None:
    if spec.kind is ParameterKind.RANGE:
        if not _number(value):
            return (
                BAD_VALUE,
                f"needs a number in [{spec.minimum:g}, {spec.maximum:g}], got {value!r}",
            )
        low = spec.minimum if spec.minimum is not None else float("-inf")
        high = spec.maximum if spec.maximum is not None else float("inf")
        if not low <= value <= high:
            return BAD_VALUE, f"needs a number in [{low:g}, {high:g}], got {value!r}"
    elif spec.kind is ParameterKind.SYMBOLS:
        if str(value) not in spec.symbols:
            return BAD_VALUE, f"needs one of {', '.join(spec.symbols)}, got {value!r}"
    elif spec.kind is ParameterKind.TYPE:
        kind = spec.type_name
        if kind == "point" and not _point(value):
            return WRONG_DIMENSIONS, f"needs a point (3 numbers), got {value!r}"
        if kind == "point_list":
            if not isinstance(value, list) or not value:
                return BAD_VALUE, f"needs a list of points, got {value!r}"
            wrong = [p for p in value if not _point(p)]
            if wrong:
                return WRONG_DIMENSIONS, f"needs points of 3 numbers, got {wrong[0]!r}"
        if kind == "string" and not isinstance(value, str):
            return BAD_VALUE, f"needs text, got {value!r}"
        if kind == "list_of_strings" and not (
            isinstance(value, list) and all(isinstance(v, str) for v in value)
        ):
            return BAD_VALUE, f"needs a list of words, got {value!r}"
    return None


@dataclass(eq=False)
class _Way:
    """One way through the tree: the coordinator's state, and who started what."""

    state: TaskState = IDLE
    #: task -> the node that started it without waiting for its end.
    unwaited: dict[str, BtNode] = field(default_factory=dict)
    steps: tuple[PathStep, ...] = ()
    #: The start the coordinator rejected, and why, while this way's failure is not yet
    #: handled (by a fallback's next child, an inverter, a succeeder...).
    rejected: tuple[BtNode, str] | None = None

    def fork(self) -> _Way:
        return _Way(self.state, dict(self.unwaited), self.steps, self.rejected)

    def handled(self) -> _Way:
        self.rejected = None
        return self


#: Ways through a tree followed at most (each fallback can double them).
MAX_WAYS = 32

#: Control nodes whose children run one after the other, each once the one before it
#: succeeded (the interpreter's sequence; BehaviorTree.CPP's reactive sequence starts
#: the same tasks in the same order).
_SEQUENCES = ("sequence", "reactive_sequence", "reactivesequence", "")
_FALLBACKS = ("fallback", "selector", "reactive_fallback", "reactivefallback")


class _TreeRun:
    """The tree run on the coordinator's model, as Aerostack's behavior-tree interpreter
    (aerostack/behavior_tree_interpreter, 2021) runs it: every node ends in success or
    failure, and each way through the tree is followed with its outcome —

    * a task node fails when the coordinator rejects its start; once started, a task
      waited for may also fail (its behavior stops without reaching its goal), which
      leaves the task stopped;
    * a sequence runs its children in order while they succeed, and fails with the
      first that fails (the later ones do not run on that way);
    * a fallback (selector) runs its children in order while they fail: the next child
      starts from the state the failed one left, and the fallback succeeds with the
      first that succeeds, or fails when all did;
    * a parallel starts its children together: the tasks of its task children overlap
      (none is waited for before the next starts);
    * an inverter swaps success and failure, a succeeder always succeeds, a repeater
      runs its child again (twice here: what a second round starts in the state of the
      first is what can go wrong), a repeat-until-fail succeeds when its child fails.

    AX717 is reported when a rejected start fails the whole mission: not when a
    fallback's next child, an inverter or a succeeder takes that failure (trying an
    alternative is what a fallback is for). AX716 is reported where a started task is
    stopped at once by a later start, whatever happens after.
    """

    def __init__(self, catalog: TaskCatalog, note: str) -> None:
        self.catalog = catalog
        self.model = TaskModel(catalog)
        self.note = note
        self.findings: dict[tuple[Any, ...], Finding] = {}

    def run(self, mission: BtMission) -> list[Finding]:
        ways = [_Way()]
        failed: list[_Way] = []
        for root in mission.roots:  # several roots: run one after the other
            ways, failures = self.visit(root, ways)
            failed.extend(failures)
        for way in failed:
            if way.rejected is not None:
                node, reason = way.rejected
                task = node.task or ""
                self.report(
                    TASK_REJECTED,
                    E,
                    f"{node.shown}: start_task({task}) is rejected: {reason}; the mission "
                    "fails there",
                    node,
                    way,
                    task,
                )
        return list(self.findings.values())

    def visit(self, node: BtNode, ways: list[_Way]) -> tuple[list[_Way], list[_Way]]:
        """(the ways on which `node` succeeds, those on which it fails)."""
        if not ways:
            return [], []
        if node.kind == "execution":
            succeeded: list[_Way] = []
            failed: list[_Way] = []
            for way in ways:
                self.start(node, way, succeeded, failed)
            return succeeded[:MAX_WAYS], failed[:MAX_WAYS]
        kind = node.subtype.casefold()
        children = node.children
        if kind in _FALLBACKS:
            remaining, succeeded = ways, []
            for child in children:
                ok, remaining = self.visit(child, [w.handled() for w in remaining])
                succeeded.extend(ok)
            return succeeded[:MAX_WAYS], remaining[:MAX_WAYS]
        if kind == "inverter":
            ok, failed = self.sequence(children, ways)
            return [w.handled() for w in failed], ok
        if kind == "succeeder":
            ok, failed = self.sequence(children, ways)
            return [*ok, *(w.handled() for w in failed)][:MAX_WAYS], []
        if kind == "repeater":
            ok, failed = self.sequence(children, ways)
            again, failed_again = self.sequence(children, [w.fork() for w in ok])
            return again, [*failed, *failed_again][:MAX_WAYS]
        if kind == "repeat_until_fail":
            ok, failed = self.sequence(children, ways)
            _, failed_again = self.sequence(children, [w.fork() for w in ok])
            return [w.handled() for w in (*failed, *failed_again)][:MAX_WAYS], []
        if kind == "parallel":
            return self.sequence(children, ways, overlap=True)
        return self.sequence(children, ways)  # a sequence, or a control node not known

    def sequence(
        self, children: list[BtNode], ways: list[_Way], overlap: bool = False
    ) -> tuple[list[_Way], list[_Way]]:
        failed: list[_Way] = []
        for child in children:
            if overlap and child.kind == "execution":
                ways, failures = self.visit(dataclasses.replace(child, wait=False), ways)
            else:
                ways, failures = self.visit(child, ways)
            failed.extend(failures)
        return ways, failed[:MAX_WAYS]

    def report(
        self, rule: str, severity: Severity, message: str, node: BtNode, way: _Way, *subjects: str
    ) -> None:
        path = "; ".join(s.describe() for s in way.steps[-8:]) or "at the start"
        finding = Finding.at(
            rule,
            severity,
            f"{message} (path: {path}){self.note}",
            node.task_mark,
            subjects,
            path=way.steps,
        )
        self.findings.setdefault((rule, node.number, finding.subjects), finding)

    def start(self, node: BtNode, way: _Way, succeeded: list[_Way], failed: list[_Way]) -> None:
        task = node.task
        if task is None or task not in self.catalog.tasks or not self.catalog.performers(task):
            succeeded.append(way)  # AX701 says so; the rest of the tree is still checked
            return
        way.steps = (
            *way.steps,
            PathStep(node.task_mark.line, node.task_mark.column, "start", task),
        )
        attempt = self.model.start_task(way.state, task)
        if attempt.accepted is None:
            succeeded.append(way)
            return
        if not attempt.accepted:
            way.rejected = (node, attempt.reason)
            failed.append(way)
            return
        running_after = {t for t, _, _ in attempt.after}
        for stopped, starter in list(way.unwaited.items()):
            if stopped != task and stopped not in running_after:
                self.report(
                    TASK_INTERRUPTED,
                    W,
                    f"{starter.shown} starts {stopped} without waiting for it, and "
                    f"{node.shown} stops it at once: {task} is mutually exclusive with "
                    f"{stopped}",
                    starter,
                    way,
                    stopped,
                    task,
                )
                del way.unwaited[stopped]
        way.state = attempt.after
        descriptor = self.catalog.tasks[task]
        ends = descriptor.execution_goal is ExecutionGoal.ACHIEVE_GOAL
        if node.wait:
            # The node ends with its task: the task's goal reached (an achieve_goal
            # task) or its behavior stopped short of it (any task: a failure).
            stopped_way = way.fork()
            stopped_way.state = frozenset(e for e in way.state if e[0] != task)
            stopped_way.unwaited.pop(task, None)
            failed.append(stopped_way)
            if ends:
                way.state = stopped_way.state
                way.unwaited.pop(task, None)
        elif ends:
            way.unwaited[task] = node
        succeeded.append(way)
