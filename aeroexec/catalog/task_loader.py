"""Read an Aerostack 4.x task catalog (2020-2021) into a `TaskCatalog`.

Lenient like the behavior catalog reader: every problem is a `Diagnostic` (AX80x) and
reading goes on. Values are read the way the 2021 coordinator's loader reads them
(cvar-upm/coordinator_cbc `catalog.cpp`, with yaml-cpp): booleans are the text "TRUE"
(anything else is false), timeouts are `as<int>()`, suitabilities `as<double>()`.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from aeroexec.catalog import task_codes as codes
from aeroexec.catalog.loader import as_float, did_you_mean, node_kind
from aeroexec.catalog.model import Diagnostic, Severity
from aeroexec.catalog.tasks import (
    ExclusionConstraint,
    ExecutionGoal,
    ParameterKind,
    ParameterSpec,
    Requirement,
    TaskBehavior,
    TaskCatalog,
    TaskDefaults,
    TaskDescriptor,
)
from aeroexec.catalog.yamlnodes import YNode
from aeroexec.errors import Mark
from aeroexec.gc_pause import paused_gc

TOP_LEVEL = ("default_values", "behaviors", "tasks", "exclusivity_constraints")
#: Task attribute keys of each vocabulary, and what each means in the model.
VOCABULARY_2021 = ("execution_goal", "start_on_request", "reactive_start", "suitability")
VOCABULARY_2020 = ("category", "automatic_activation", "default", "efficacy")
TASK_TAGS = ("task", "timeout", "parameters", *VOCABULARY_2021[:3], *VOCABULARY_2020[:3])
BEHAVIOR_TAGS = ("behavior", "package", "task", "requires", "suitability", "efficacy")
REQUIREMENT_TAGS = ("task", "minimum_performance")
#: `allowed_value` is the key the 2021 coordinator's code reads (no catalog writes it).
PARAMETER_TAGS = ("parameter", "allowed_values", "allowed_value", "dimensions")
DEFAULT_TASK_TAGS = ("timeout", *VOCABULARY_2021[:3], *VOCABULARY_2020[:3])
DEFAULT_BEHAVIOR_TAGS = ("suitability", "efficacy")
#: Keys that belong to a parameter; found on a task they are misindented.
PARAMETER_ONLY = ("allowed_values", "allowed_value", "dimensions", "parameter")
_GOALS_2020 = {"goal_based": ExecutionGoal.ACHIEVE_GOAL, "recurrent": ExecutionGoal.KEEP_RUNNING}
_BOOLEAN_WORDS = {"true", "false", "yes", "no", "on", "off", "y", "n"}
MAX_INT = 2**31 - 1


def is_task_catalog(root: YNode) -> bool:
    """A mapping with `behaviors` and at least one of `tasks`/`default_values`/
    `exclusivity_constraints`, and no 2017 `behavior_descriptors`."""
    keys = set(root.value) if root.is_map else set()
    if "behavior_descriptors" in keys or "behaviors" not in keys:
        return False
    return bool({"tasks", "default_values", "exclusivity_constraints"} & keys)


def read_task_catalog(root: YNode, file: str, text: str = "") -> TaskCatalog:
    with paused_gc():
        return _TaskReader(file, text).read(root)


class _TaskReader:
    def __init__(self, file: str, text: str) -> None:
        self.file = file
        self.text = text
        self.diagnostics: list[Diagnostic] = []
        self.defaults = TaskDefaults()
        #: First place each vocabulary's keys are used.
        self.used_2020: list[tuple[str, Mark]] = []
        self.used_2021: list[tuple[str, Mark]] = []

    # -- reporting -----------------------------------------------------------------------
    def report(
        self, code: str, severity: Severity, message: str, mark: Mark, *subjects: str
    ) -> None:
        self.diagnostics.append(Diagnostic(code, severity, message, mark, tuple(subjects)))

    def error(self, code: str, message: str, mark: Mark, *subjects: str) -> None:
        self.report(code, Severity.ERROR, message, mark, *subjects)

    def check_keys(self, node: YNode, known: tuple[str, ...], where: str, *subjects: str) -> None:
        for key, mark in node.key_marks.items():
            if key in VOCABULARY_2020 and key in known:
                self.used_2020.append((key, mark))
            elif key in VOCABULARY_2021 and key in known:
                self.used_2021.append((key, mark))
            if key in known:
                continue
            self.report(
                codes.TASK_UNKNOWN_TAG,
                Severity.WARNING,
                f"unknown tag '{key}' in {where}{did_you_mean(key, known)}",
                mark,
                *subjects,
            )

    # -- typed values --------------------------------------------------------------------
    def name(self, node: YNode | None, what: str, *subjects: str) -> str | None:
        if node is None:
            return None
        value = node.text
        if isinstance(value, (str, int, float)) and not isinstance(value, bool) and str(value):
            return str(value)
        self.error(
            codes.TASK_WRONG_TYPE,
            f"{what} must be a name, got {node_kind(node)}",
            node.mark,
            *subjects,
        )
        return None

    def entries(self, node: YNode | None, what: str) -> list[YNode]:
        if node is None or node.value is None:
            return []
        if not node.is_list:
            self.error(
                codes.TASK_WRONG_TYPE, f"{what} must be a list, got {node_kind(node)}", node.mark
            )
            return []
        good = []
        for item in node.value:
            if item.is_map:
                good.append(item)
            else:
                self.error(
                    codes.TASK_WRONG_TYPE,
                    f"each entry of {what} must be a mapping, got {node_kind(item)}",
                    item.mark,
                )
        return good

    def boolean(self, node: YNode, what: str, *subjects: str) -> bool | None:
        text = node.text
        if text in ("TRUE", "FALSE"):
            return text == "TRUE"
        if isinstance(node.value, bool) or (
            isinstance(text, str) and text.casefold() in _BOOLEAN_WORDS
        ):
            self.report(
                codes.BOOLEAN_SPELLING,
                Severity.WARNING,
                f"{what} is '{text}', not TRUE or FALSE: the coordinator compares the text "
                "with TRUE, so this means FALSE",
                node.mark,
                *subjects,
            )
            return False
        self.error(
            codes.TASK_WRONG_TYPE,
            f"{what} must be TRUE or FALSE, got {node_kind(node)}",
            node.mark,
            *subjects,
        )
        return None

    def timeout(self, node: YNode, what: str, *subjects: str) -> float | None:
        value = node.value
        if isinstance(value, int) and not isinstance(value, bool) and 0 < value <= MAX_INT:
            return float(value)
        self.error(
            codes.TASK_WRONG_TYPE,
            f"{what} must be a whole number of seconds in 1..{MAX_INT} (the coordinator "
            f"reads it as an int and stops loading otherwise), got {node_kind(node)}",
            node.mark,
            *subjects,
        )
        return None

    def percent(self, node: YNode, what: str, *subjects: str) -> float | None:
        value = node.value
        if isinstance(value, (int, float)) and not isinstance(value, bool) and 0 <= value <= 100:
            return float(value)
        self.error(
            codes.TASK_WRONG_TYPE,
            f"{what} must be a percentage in 0..100, got {node_kind(node)}",
            node.mark,
            *subjects,
        )
        return None

    def goal(self, node: YNode, key: str, *subjects: str) -> ExecutionGoal | None:
        # Only a word can name a goal: a mapping or list must not reach the dict lookup
        # (unhashable) nor the enum.
        value = node.text if isinstance(node.text, str) else None
        if key == "execution_goal":
            if value in ("achieve_goal", "keep_running"):
                return ExecutionGoal(value)
            expected = "achieve_goal or keep_running"
        else:
            if value in _GOALS_2020:
                return _GOALS_2020[value]
            expected = "goal_based or recurrent"
        self.error(
            codes.TASK_WRONG_TYPE,
            f"{key} must be {expected}, got {node_kind(node)}",
            node.mark,
            *subjects,
        )
        return None

    # -- attributes shared by tasks and the task defaults --------------------------------
    def attributes(self, node: YNode, where: str, *subjects: str) -> dict[str, Any]:
        """The task attributes written on `node`, in the model's terms."""
        found: dict[str, Any] = {}
        for key in ("execution_goal", "category"):
            if (value := node.get(key)) is not None:
                goal = self.goal(value, key, *subjects)
                if goal is not None:
                    found["execution_goal"] = goal
        if (value := node.get("start_on_request")) is not None:
            flag = self.boolean(value, f"{where}: start_on_request", *subjects)
            if flag is not None:
                found["start_on_request"] = flag
        if (value := node.get("automatic_activation")) is not None:
            flag = self.boolean(value, f"{where}: automatic_activation", *subjects)
            if flag is not None:
                found["start_on_request"] = not flag
        for key in ("reactive_start", "default"):
            if (value := node.get(key)) is not None:
                flag = self.boolean(value, f"{where}: {key}", *subjects)
                if flag is not None:
                    found["reactive_start"] = flag
        if (value := node.get("timeout")) is not None:
            seconds = self.timeout(value, f"{where}: timeout", *subjects)
            if seconds is not None:
                found["timeout"] = seconds
        return found

    # -- sections ------------------------------------------------------------------------
    def read(self, root: YNode) -> TaskCatalog:
        self.check_keys(root, TOP_LEVEL, "the task catalog")
        for key, mark in root.duplicate_keys:
            self.report(
                codes.TASK_UNKNOWN_TAG,
                Severity.WARNING,
                f"duplicate key '{key}' in the task catalog; the last value is used",
                mark,
            )
        self._read_defaults(root.get("default_values"))
        behaviors = [
            b for b in map(self._behavior, self.entries(root.get("behaviors"), "behaviors")) if b
        ]
        declarations = [t for t in map(self._task, self.entries(root.get("tasks"), "tasks")) if t]
        exclusions = [
            c
            for c in map(
                self._exclusion,
                self.entries(root.get("exclusivity_constraints"), "exclusivity_constraints"),
            )
            if c
        ]
        tasks = self._effective_tasks(behaviors, declarations)
        self._report_duplicate_behaviors(behaviors)
        dialect = self._report_vocabulary(root)
        return TaskCatalog(
            behaviors=tuple(behaviors),
            tasks=tasks,
            exclusions=tuple(exclusions),
            defaults=self.defaults,
            declarations=tuple(declarations),
            source=self.file,
            dialect=dialect,
            text=self.text,
            diagnostics=tuple(self.diagnostics),
            section_marks=dict(root.key_marks),
        )

    def _read_defaults(self, node: YNode | None) -> None:
        if node is None or node.value is None:
            return
        # Written as a list of one-key mappings (`- tasks: [...]`, `- behaviors: [...]`);
        # a plain mapping means the same.
        blocks: list[tuple[str, YNode, Mark]] = []
        if node.is_map:
            blocks = [(k, v, node.key_marks[k]) for k, v in node.items()]
        elif node.is_list:
            for item in node.value:
                if not item.is_map:
                    self.error(
                        codes.TASK_WRONG_TYPE,
                        f"each entry of default_values must be a mapping, got {node_kind(item)}",
                        item.mark,
                    )
                    continue
                blocks += [(k, v, item.key_marks[k]) for k, v in item.items()]
        else:
            self.error(
                codes.TASK_WRONG_TYPE,
                f"default_values must be a list, got {node_kind(node)}",
                node.mark,
            )
            return
        attributes: dict[str, Any] = {}
        for key, value, mark in blocks:
            if key not in ("tasks", "behaviors"):
                self.report(
                    codes.TASK_UNKNOWN_TAG,
                    Severity.WARNING,
                    f"unknown tag '{key}' in default_values"
                    + did_you_mean(key, ("tasks", "behaviors")),
                    mark,
                )
                continue
            for entry in value.value if value.is_list else [value]:
                if not entry.is_map:
                    self.error(
                        codes.TASK_WRONG_TYPE,
                        f"default_values {key} must be mappings, got {node_kind(entry)}",
                        entry.mark,
                    )
                    continue
                if key == "tasks":
                    self.check_keys(entry, DEFAULT_TASK_TAGS, "default_values tasks")
                    attributes.update(self.attributes(entry, "default_values tasks"))
                else:
                    self.check_keys(entry, DEFAULT_BEHAVIOR_TAGS, "default_values behaviors")
                    for word in DEFAULT_BEHAVIOR_TAGS:
                        if (found := entry.get(word)) is not None:
                            share = self.percent(found, f"default {word}")
                            if share is not None:
                                attributes["suitability"] = share
        defaults = TaskDefaults()
        self.defaults = TaskDefaults(
            execution_goal=attributes.get("execution_goal", defaults.execution_goal),
            start_on_request=attributes.get("start_on_request", defaults.start_on_request),
            reactive_start=attributes.get("reactive_start", defaults.reactive_start),
            timeout=attributes.get("timeout", defaults.timeout),
            suitability=attributes.get("suitability", defaults.suitability),
        )

    def _behavior(self, node: YNode) -> TaskBehavior | None:
        name = self.name(node.get("behavior"), "behavior")
        if name is None:
            if node.get("behavior") is None:
                self.error(
                    codes.TASK_MISSING_TAG,
                    "a behavior entry has no 'behavior' (its name)",
                    node.mark,
                )
            return None
        self.check_keys(node, BEHAVIOR_TAGS, f"behavior {name}", name)
        marks: dict[str, Mark] = dict(node.key_marks)
        task_node = node.get("task")
        task = self.name(task_node, f"{name}: task", name)
        if task_node is None:
            self.error(
                codes.TASK_MISSING_TAG,
                f"behavior {name} has no task: the coordinator reports 'The behavior: {name} "
                "has no task defined' and stops reading the catalog at this entry",
                node.mark,
                name,
            )
        elif task is not None:
            marks["task.value"] = task_node.mark
        suitability = self.defaults.suitability
        for word in ("suitability", "efficacy"):
            if (found := node.get(word)) is not None:
                share = self.percent(found, f"{name}: {word}", name)
                if share is not None:
                    suitability = share
        package = self.name(node.get("package"), f"{name}: package", name) or ""
        requires = tuple(self._requirements(node.get("requires"), name))
        return TaskBehavior(name, task, suitability, package, requires, node.mark, marks)

    def _requirements(self, node: YNode | None, behavior: str) -> Iterator[Requirement]:
        for entry in self.entries(node, f"{behavior}: requires"):
            self.check_keys(entry, REQUIREMENT_TAGS, f"a requirement of {behavior}", behavior)
            task_node = entry.get("task")
            if task_node is None:
                self.error(
                    codes.TASK_MISSING_TAG,
                    f"a requirement of {behavior} names no 'task'",
                    entry.mark,
                    behavior,
                )
                continue
            task = self.name(task_node, f"{behavior}: required task", behavior)
            if task is None:
                continue
            minimum = 0.0
            if (found := entry.get("minimum_performance")) is not None:
                share = self.percent(found, f"{behavior}: minimum_performance", behavior)
                minimum = share if share is not None else 0.0
            yield Requirement(task, minimum, task_node.mark)

    def _task(self, node: YNode) -> TaskDescriptor | None:
        name = self.name(node.get("task"), "task")
        if name is None:
            if node.get("task") is None:
                self.error(
                    codes.TASK_MISSING_TAG, "a task entry has no 'task' (its name)", node.mark
                )
            return None
        self.check_keys(node, (*TASK_TAGS, *PARAMETER_ONLY), f"task {name}", name)
        written = self.attributes(node, name, name)
        defaults = self.defaults
        parameters = self._parameters(node.get("parameters"), name)
        self._misindented(node, name, parameters)
        marks = dict(node.key_marks)
        for key, canonical in (
            ("category", "execution_goal"),
            ("automatic_activation", "start_on_request"),
            ("default", "reactive_start"),
        ):
            if key in marks and canonical not in marks:
                marks[canonical] = marks[key]
        return TaskDescriptor(
            name=name,
            execution_goal=written.get("execution_goal", defaults.execution_goal),
            start_on_request=written.get("start_on_request", defaults.start_on_request),
            reactive_start=written.get("reactive_start", defaults.reactive_start),
            timeout=written.get("timeout", defaults.timeout),
            parameters=parameters,
            declared=True,
            mark=node.mark,
            marks=marks,
        )

    def _parameters(self, node: YNode | None, task: str) -> tuple[ParameterSpec, ...]:
        specs: list[ParameterSpec] = []
        for entry in self.entries(node, f"{task}: parameters"):
            self.check_keys(entry, PARAMETER_TAGS, f"a parameter of {task}", task)
            name = self.name(entry.get("parameter"), f"{task}: parameter", task)
            if name is None:
                if entry.get("parameter") is None:
                    self.error(
                        codes.TASK_MISSING_TAG,
                        f"a parameter of {task} has no 'parameter' (its name)",
                        entry.mark,
                        task,
                    )
                continue
            allowed = entry.get("allowed_values")
            if allowed is None:
                allowed = entry.get("allowed_value")
            specs.append(self._spec(task, name, allowed, entry.mark))
        return tuple(specs)

    def _spec(self, task: str, name: str, allowed: YNode | None, mark: Mark) -> ParameterSpec:
        def malformed(problem: str, where: Mark) -> ParameterSpec:
            self.error(
                codes.MALFORMED_PARAMETER, f"{task}: parameter {name}: {problem}", where, task
            )
            return ParameterSpec(name, ParameterKind.INVALID, mark=mark)

        if allowed is None or allowed.value is None:
            return ParameterSpec(name, ParameterKind.UNSPECIFIED, mark=mark)
        if isinstance(allowed.text, str) and not allowed.is_list:
            return ParameterSpec(name, ParameterKind.TYPE, type_name=allowed.text, mark=mark)
        if not allowed.is_list or not allowed.value:
            return malformed(
                f"allowed_values must be [min, max], a list of words or a type word, got "
                f"{node_kind(allowed)}",
                allowed.mark,
            )
        values = [v.text for v in allowed.value]
        numbers = [v for v in values if isinstance(v, (int, float)) and not isinstance(v, bool)]
        if len(numbers) == len(values):
            if len(values) != 2:
                return malformed(
                    f"a numeric range is [min, max], got {len(values)} numbers", allowed.mark
                )
            low, high = as_float(values[0]), as_float(values[1])
            if low is None or high is None:
                return malformed("a range bound is NaN or too large for a float", allowed.mark)
            if not low <= high:
                return malformed(
                    f"empty range [{values[0]}, {values[1]}] (min > max)", allowed.mark
                )
            return ParameterSpec(name, ParameterKind.RANGE, low, high, mark=mark)
        if all(isinstance(v, str) and v for v in values):
            if len(set(values)) != len(values):
                return malformed("a word is listed twice", allowed.mark)
            return ParameterSpec(name, ParameterKind.SYMBOLS, symbols=tuple(values), mark=mark)
        return malformed("allowed_values mixes numbers and words", allowed.mark)

    def _misindented(self, node: YNode, task: str, parameters: tuple[ParameterSpec, ...]) -> None:
        for key in PARAMETER_ONLY:
            mark = node.key_marks.get(key)
            if mark is None:
                continue
            before = [p for p in parameters if p.mark.line and p.mark.line < mark.line]
            if before:
                last = before[-1]
                where = (
                    f"it is indented as a key of the task, not under '- parameter: "
                    f"{last.name}' (line {last.mark.line}), which gets no {key}"
                    if last.kind is ParameterKind.UNSPECIFIED
                    else "it is indented as a key of the task, not under a '- parameter:' entry"
                )
            else:
                where = "it belongs under a '- parameter:' entry of 'parameters'"
            self.report(
                codes.MISINDENTED_PARAMETER,
                Severity.WARNING,
                f"task {task}: '{key}' is not a task attribute; {where}",
                mark,
                task,
                *(p.name for p in before[-1:]),
            )

    def _exclusion(self, node: YNode) -> ExclusionConstraint | None:
        self.check_keys(node, ("mutually_exclusive",), "an exclusivity constraint")
        members = node.get("mutually_exclusive")
        if members is None:
            self.error(
                codes.TASK_MISSING_TAG,
                "an exclusivity constraint has no 'mutually_exclusive' list",
                node.mark,
            )
            return None
        if not members.is_list:
            self.error(
                codes.TASK_WRONG_TYPE,
                f"mutually_exclusive must be a list of tasks, got {node_kind(members)}",
                members.mark,
            )
            return None
        names: list[str] = []
        marks: dict[str, Mark] = {}
        for item in members.value:
            name = self.name(item, "a mutually exclusive task")
            if name is not None:
                marks[f"tasks.{len(names)}"] = item.mark
                names.append(name)
        return ExclusionConstraint(tuple(names), node.mark, marks)

    # -- the catalog as the coordinator holds it -----------------------------------------
    def _effective_tasks(
        self, behaviors: list[TaskBehavior], declarations: list[TaskDescriptor]
    ) -> dict[str, TaskDescriptor]:
        tasks: dict[str, TaskDescriptor] = {}
        for behavior in behaviors:
            if behavior.task is not None and behavior.task not in tasks:
                # Performed but (so far) undeclared: the coordinator's own Task defaults
                # (start on request, no reactive start) with the default timeout.
                tasks[behavior.task] = TaskDescriptor(
                    name=behavior.task,
                    execution_goal=ExecutionGoal.ACHIEVE_GOAL,
                    start_on_request=True,
                    reactive_start=False,
                    timeout=self.defaults.timeout,
                    declared=False,
                    mark=behavior.mark_of("task.value"),
                )
        first_line: dict[str, int] = {}
        for declaration in declarations:
            name = declaration.name
            if name in first_line:
                self.report(
                    codes.DUPLICATE_TASK,
                    Severity.WARNING,
                    f"task {name} is declared again (first at line {first_line[name]}); the "
                    "coordinator applies this declaration (and the defaults for what it "
                    "leaves out) to the same task",
                    declaration.mark,
                    name,
                )
                earlier = tasks[name]
                declaration = TaskDescriptor(
                    name=name,
                    execution_goal=declaration.execution_goal,
                    start_on_request=declaration.start_on_request,
                    reactive_start=declaration.reactive_start,
                    timeout=declaration.timeout,
                    parameters=earlier.parameters + declaration.parameters,
                    declared=True,
                    mark=declaration.mark,
                    marks=declaration.marks,
                )
            else:
                first_line[name] = declaration.mark.line
            tasks[name] = declaration
        return tasks

    def _report_duplicate_behaviors(self, behaviors: list[TaskBehavior]) -> None:
        first: dict[str, int] = {}
        for behavior in behaviors:
            if behavior.name in first:
                self.report(
                    codes.DUPLICATE_TASK_BEHAVIOR,
                    Severity.WARNING,
                    f"behavior {behavior.name} is listed again (first at line "
                    f"{first[behavior.name]}): the coordinator keeps both as candidates, "
                    "but starts, stops and reports behaviors by name",
                    behavior.mark,
                    behavior.name,
                )
            else:
                first[behavior.name] = behavior.mark.line

    def _report_vocabulary(self, root: YNode) -> str:
        if self.used_2020 and self.used_2021:
            key_2020, mark_2020 = self.used_2020[0]
            key_2021, mark_2021 = self.used_2021[0]
            self.report(
                codes.MIXED_VOCABULARY,
                Severity.WARNING,
                f"the catalog mixes the 2020 vocabulary ('{key_2020}', line {mark_2020.line}) "
                f"with the 2021 one ('{key_2021}', line {mark_2021.line}): the 2021 "
                f"coordinator ignores '{key_2020}'",
                mark_2020,
            )
            dialect = "mixed"
        elif self.used_2020:
            dialect = "aerostack-4.0-2020"
        else:
            dialect = "cbc-2021"
        described = {
            "aerostack-4.0-2020": "the 2020 vocabulary (category, default, automatic_activation, "
            "efficacy; Aerostack 4.0's behavior manager) — the 2021 coordinator reads none "
            "of these keys",
            "cbc-2021": "the 2021 vocabulary (execution_goal, reactive_start, "
            "start_on_request, suitability; the CBC coordinator)",
            "mixed": "a mix of the 2020 and 2021 vocabularies",
        }
        self.report(
            codes.TASK_VOCABULARY,
            Severity.INFO,
            f"read as an Aerostack 4.x task catalog in {described[dialect]}",
            root.mark,
        )
        return dialect
