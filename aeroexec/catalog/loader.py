"""Read a behavior catalog (thesis Appendix A dialect or flown Aerostack 2.x) into a `Catalog`.

`read_catalog` is lenient: it reports every problem as a `Diagnostic` and keeps going
(the verifier wants all of them). `load_catalog` is what the executive uses: it raises
`CatalogError` for the first error-class diagnostic, like the thesis' specialist.
Only unreadable input (missing file, invalid YAML, not a mapping, another catalog
format) raises from `read_catalog`.
"""

from __future__ import annotations

import difflib
import math
import sys
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any, NamedTuple

from aeroexec.catalog import codes
from aeroexec.catalog.model import (
    DEFAULT_TIMEOUT_S,
    MAX_TIMEOUT_S,
    ArgumentKind,
    ArgumentSpec,
    BehaviorDescriptor,
    BehaviorList,
    CapabilityDescriptor,
    Catalog,
    Diagnostic,
    Marks,
    PackedMarks,
    Severity,
)
from aeroexec.catalog.yamlnodes import YNode, load_yaml, short_repr
from aeroexec.errors import CatalogError, Mark
from aeroexec.gc_pause import paused_gc
from aeroexec.inputs import read_text

TOP_LEVEL_TAGS = (
    "behavior_descriptors",
    "behavior_lists",
    "capability_descriptors",
    "default_behavior_values",
    "reactive_activation",
)
BEHAVIOR_TAGS = (
    "behavior",
    "timeout",
    "recurrent",
    "category",
    "incompatible_lists",
    "capabilities",
    "arguments",
)
LIST_TAGS = ("list", "behaviors")
CAPABILITY_TAGS = (
    "capability",
    "processes",
    "process_sequence",
    "active_by_default",
    "incompatible_capabilities",
    "required_capabilities",
)
ARGUMENT_TAGS = ("argument", "allowed_values", "dimensions")
DEFAULT_VALUES_TAGS = ("timeout", "category")
#: Spellings seen in real catalogs that mean a known tag: accepted, with a warning.
ALIASES = {"activate_by_default": "active_by_default"}

_TRUE = {"yes", "true", "on", "y"}
_FALSE = {"no", "false", "off", "n"}


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """` (did you mean 'x'?)` or '' — for unknown names in every message."""
    pool = list(choices)
    close = difflib.get_close_matches(word, pool, n=1, cutoff=0.6)
    if not close:
        folded = {c.casefold(): c for c in pool}
        if word.casefold() in folded:
            close = [folded[word.casefold()]]
    return f" (did you mean '{close[0]}'?)" if close else ""


def read_catalog_text(path: str | Path) -> tuple[str, str]:
    """The catalog's text and the name to show for it; `CatalogError` if unreadable
    (missing, not a regular file, too large, not UTF-8)."""
    return read_text(path, "a catalog file", CatalogError), str(path)


def read_catalog(path: str | Path) -> Catalog:
    """Load leniently: every content problem becomes a diagnostic on the result."""
    text, file = read_catalog_text(path)
    return parse_catalog(text, file)


def load_catalog(path: str | Path) -> Catalog:
    """Load strictly: the first error-class diagnostic raises `CatalogError`."""
    return strict(read_catalog(path))


def strict(catalog: Catalog) -> Catalog:
    for diagnostic in catalog.diagnostics:
        if diagnostic.severity is Severity.ERROR:
            raise CatalogError(f"{diagnostic.message} [{diagnostic.code}]", diagnostic.mark)
    return catalog


def parse_catalog(text: str, file: str = "<string>") -> Catalog:
    return parse_root(load_yaml(text, file), text, file)


def parse_root(root: YNode | None, text: str, file: str) -> Catalog:
    """A behavior catalog from its parsed YAML; `CatalogError` for another format."""
    if root is None:
        raise CatalogError("empty document: a catalog needs behavior_descriptors", Mark(file, 1, 1))
    if not root.is_map:
        raise CatalogError(
            f"a catalog is a mapping with behavior_descriptors, got a {_kind(root)}", root.mark
        )
    _refuse_other_formats(root)
    with paused_gc():
        return _CatalogReader(file, text).read(root)


def _refuse_other_formats(root: YNode) -> None:
    keys = set(root.value)
    if "behavior_descriptors" in keys:
        return
    if "behaviors" in keys and ({"tasks", "default_values", "exclusivity_constraints"} & keys):
        # The executive is the 2017 coordinator (lists, capabilities, preemption); a
        # task catalog needs the 2021 constraint-based assignment of behaviors to tasks,
        # which it does not implement. `aeroexec verify` reads and checks task catalogs.
        raise CatalogError(
            "this is an Aerostack 4.x task-based catalog (behaviors/tasks/default_values, "
            "2020-2021), not a behavior catalog: aeroexec's executive runs the 2017 "
            "behavior coordinator (the thesis and Aerostack 2.x formats: "
            "behavior_descriptors/behavior_lists/capability_descriptors), not the 2021 "
            "task coordinator; `aeroexec verify` checks task catalogs",
            root.mark,
        )


def node_kind(node: YNode) -> str:
    """`mapping`, `list`, `null` or `int (5)`: what a value is, for messages (a long
    value cut short)."""
    return _kind(node)


def _kind(node: YNode) -> str:
    if node.is_map:
        return "mapping"
    if node.is_list:
        return "list"
    if node.value is None:
        return "null"
    return f"{type(node.value).__name__} ({short_repr(node.value)})"


class NameRefs(NamedTuple):
    """A list of names as read, and where each was written."""

    names: tuple[str, ...]
    marks: Sequence[Mark]


NO_NAMES = NameRefs((), ())


class _CatalogReader:
    def __init__(self, file: str, text: str) -> None:
        self.file = file
        self.text = text
        self.diagnostics: list[Diagnostic] = []
        self.default_timeout: float | None = None
        self.default_recurrent: bool | None = None
        self.saw_thesis_tags = False
        self.saw_flown_tags = False

    # -- reporting -----------------------------------------------------------------------
    def report(
        self, code: str, severity: Severity, message: str, mark: Mark, *subjects: str
    ) -> None:
        self.diagnostics.append(Diagnostic(code, severity, message, mark, tuple(subjects)))

    def error(self, code: str, message: str, mark: Mark, *subjects: str) -> None:
        self.report(code, Severity.ERROR, message, mark, *subjects)

    def check_keys(self, node: YNode, known: tuple[str, ...], where: str, *subjects: str) -> None:
        for key, mark in node.key_marks.items():
            if key in known:
                continue
            if key in ALIASES and ALIASES[key] in known:
                self.report(
                    codes.UNKNOWN_TAG,
                    Severity.WARNING,
                    f"'{key}' is not a catalog tag in {where}; read as '{ALIASES[key]}'",
                    mark,
                    *subjects,
                )
                continue
            self.report(
                codes.UNKNOWN_TAG,
                Severity.WARNING,
                f"unknown tag '{key}' in {where}{did_you_mean(key, known)}",
                mark,
                *subjects,
            )
        for key, mark in node.duplicate_keys:
            self.report(
                codes.DUPLICATE_KEY,
                Severity.WARNING,
                f"duplicate key '{key}' in {where}; the last value is used",
                mark,
                *subjects,
            )

    def dependency(self, node: YNode, tag: str, owner: str, *subjects: str) -> YNode | None:
        """A dependency tag's value; the thesis says an absent one gets an info message."""
        value = node.get(tag)
        if value is None and tag not in node.value:
            self.report(
                codes.MISSING_DEPENDENCY_TAG,
                Severity.INFO,
                f"{owner}: no {tag}; none is assumed",
                node.mark,
                *subjects,
            )
        return value

    def tag(self, node: YNode, name: str) -> YNode | None:
        """The value of `name`, or of its accepted alias spelling."""
        found = node.get(name)
        if found is not None:
            return found
        for alias, canonical in ALIASES.items():
            if canonical == name and node.get(alias) is not None:
                return node.get(alias)
        return None

    # -- typed values --------------------------------------------------------------------
    def name_of(self, node: YNode, what: str, *subjects: str) -> str | None:
        value = node.value
        if isinstance(value, (str, int, float)) and not isinstance(value, bool) and str(value):
            # Interned: a name is looked up in the executive's indexes a dozen times per
            # activation, and with one string object per name (the mission's literals
            # too) each lookup compares pointers, not characters in cold memory.
            return sys.intern(str(value))
        self.error(
            codes.WRONG_TYPE, f"{what} must be a name, got {_kind(node)}", node.mark, *subjects
        )
        return None

    def names(self, node: YNode | None, what: str, *subjects: str) -> NameRefs:
        """The names of a list (a single name warned about), and the mark of each."""
        if node is None or node.value is None:
            return NO_NAMES
        items = node.value if node.is_list else [node]
        if not node.is_list and not isinstance(node.value, str):
            self.error(
                codes.WRONG_TYPE,
                f"{what} must be a list of names, got {_kind(node)}",
                node.mark,
                *subjects,
            )
            return NO_NAMES
        if not node.is_list:
            self.report(
                codes.SCALAR_FOR_LIST,
                Severity.WARNING,
                f"{what} is a single name, not a list: aeroexec reads it as "
                f"[{node.value}], Aerostack's yaml-cpp loaders iterated it as an empty "
                f"list; write [{node.value}]",
                node.mark,
                *subjects,
            )
        # The names, and their marks packed (not a (name, Mark) pair per item): a list
        # a million names long costs the names and eight bytes each.
        names: list[str] = []
        marks = PackedMarks(node.file)
        lines, columns = marks.lines, marks.columns
        intern = sys.intern
        for item in items:
            value = item.value
            if value.__class__ is str and value:  # the usual name, without a call
                name: str | None = intern(value)
            else:
                name = self.name_of(item, f"an entry of {what}", *subjects)
                if name is None:
                    continue
            names.append(name)  # type: ignore[arg-type]
            lines.append(item.line)
            columns.append(item.column)
        return NameRefs(tuple(names), marks)

    def boolean(self, node: YNode, what: str, *subjects: str) -> bool | None:
        value = node.value
        if isinstance(value, bool):
            return value
        if isinstance(value, str) and value.casefold() in _TRUE | _FALSE:
            return value.casefold() in _TRUE
        self.error(
            codes.WRONG_TYPE, f"{what} must be yes or no, got {_kind(node)}", node.mark, *subjects
        )
        return None

    def seconds(self, node: YNode, what: str, *subjects: str) -> float | None:
        value = as_float(node.value)
        if value is not None and 0 < value <= MAX_TIMEOUT_S:
            return value
        if value is not None and value > MAX_TIMEOUT_S:
            # `.inf` and 1e300 pass "positive" but the executive's clock cannot arm
            # them: the deadline in nanoseconds overflows.
            problem = f"at most {MAX_TIMEOUT_S:.3g} s (the executive's clock counts int64 ns)"
            self.error(
                codes.WRONG_TYPE,
                f"{what} must be {problem}, got {_kind(node)}",
                node.mark,
                *subjects,
            )
            return None
        self.error(
            codes.WRONG_TYPE,
            f"{what} must be a positive number of seconds, got {_kind(node)}",
            node.mark,
            *subjects,
        )
        return None

    def category(self, node: YNode, *subjects: str) -> bool | None:
        """2.x `category: goal_based|recurrent` -> recurrent flag."""
        value = node.value
        if isinstance(value, str) and value in ("goal_based", "recurrent"):
            return value == "recurrent"
        self.error(
            codes.WRONG_TYPE,
            f"category must be goal_based or recurrent, got {_kind(node)}",
            node.mark,
            *subjects,
        )
        return None

    def entries(self, root: YNode, section: str) -> list[YNode]:
        node = root.get(section)
        if node is None or node.value is None:
            return []
        if not node.is_list:
            self.error(codes.WRONG_TYPE, f"{section} must be a list, got {_kind(node)}", node.mark)
            return []
        good = []
        for item in node.value:
            if item.is_map:
                good.append(item)
            else:
                self.error(
                    codes.WRONG_TYPE,
                    f"each entry of {section} must be a mapping, got {_kind(item)}",
                    item.mark,
                )
        return good

    # -- sections ------------------------------------------------------------------------
    def read(self, root: YNode) -> Catalog:
        self.check_keys(root, TOP_LEVEL_TAGS, "the catalog")
        for section in ("behavior_descriptors", "capability_descriptors"):
            if section not in root.value:
                self.error(
                    codes.MISSING_ERROR_TAG,
                    f"missing '{section}' (an error tag: the catalog cannot load without it)",
                    root.mark,
                )
        self._read_defaults(root)
        if "reactive_activation" in root.value:
            self.report(
                codes.IGNORED_SECTION,
                Severity.INFO,
                "reactive_activation is read but not acted on by aeroexec",
                root.key_marks["reactive_activation"],
            )
        behaviors = [
            b for b in map(self._behavior, self.entries(root, "behavior_descriptors")) if b
        ]
        lists = [x for x in map(self._list, self.entries(root, "behavior_lists")) if x]
        capabilities = [
            c for c in map(self._capability, self.entries(root, "capability_descriptors")) if c
        ]
        self._report_dialect(root)
        return Catalog(
            behaviors=self._unique(behaviors, "behavior"),
            lists=self._unique(lists, "list"),
            capabilities=self._unique(capabilities, "capability"),
            source=self.file,
            dialect=self.dialect,
            text=self.text,
            diagnostics=tuple(self.diagnostics),
            all_behaviors=tuple(behaviors),
            all_lists=tuple(lists),
            all_capabilities=tuple(capabilities),
            section_marks=dict(root.key_marks),
        )

    @property
    def dialect(self) -> str:
        if self.saw_flown_tags and self.saw_thesis_tags:
            return "mixed"
        if self.saw_flown_tags:
            return "aerostack-2.x"
        return "thesis-2017"

    def _report_dialect(self, root: YNode) -> None:
        descriptions = {
            "thesis-2017": "thesis 2017 dialect (recurrent, processes, active_by_default)",
            "aerostack-2.x": "Aerostack 2.x dialect (default_behavior_values, category, "
            "process_sequence)",
            "mixed": "a mix of the thesis 2017 and Aerostack 2.x dialects",
        }
        self.report(
            codes.DIALECT, Severity.INFO, f"read as {descriptions[self.dialect]}", root.mark
        )

    def _unique(self, items: list[Any], kind: str) -> dict[str, Any]:
        """Later definitions win, as in the real specialist's std::map; each is reported."""
        by_name: dict[str, Any] = {}
        for item in items:
            if item.name in by_name:
                first = by_name[item.name]
                self.report(
                    codes.DUPLICATE_DEFINITION,
                    Severity.WARNING,
                    f"{kind} {item.name} is defined again (first at line {first.mark.line}); "
                    "this later definition is used",
                    item.mark,
                    item.name,
                )
                del by_name[item.name]  # keep file order of the surviving definition
            by_name[item.name] = item
        return by_name

    def _read_defaults(self, root: YNode) -> None:
        block = root.get("default_behavior_values")
        if block is None:
            return
        self.saw_flown_tags = True
        if not block.is_map:
            self.error(
                codes.WRONG_TYPE,
                f"default_behavior_values must be a mapping, got {_kind(block)}",
                block.mark,
            )
            return
        self.check_keys(block, DEFAULT_VALUES_TAGS, "default_behavior_values")
        if (timeout := block.get("timeout")) is not None:
            self.default_timeout = self.seconds(timeout, "default timeout")
        if (category := block.get("category")) is not None:
            self.default_recurrent = self.category(category)

    def _required_name(self, node: YNode, tag: str, where: str, *subjects: str) -> str | None:
        value = node.get(tag)
        if value is None:
            self.error(
                codes.MISSING_ERROR_TAG,
                f"{where} has no '{tag}' (an error tag){self._nearby(node, tag)}",
                node.mark,
                *subjects,
            )
            return None
        return self.name_of(value, f"'{tag}'", *subjects)

    def _nearby(self, node: YNode, tag: str) -> str:
        """Mention a misspelt key that was probably meant as `tag`."""
        for key in node.value:
            if difflib.get_close_matches(tag, [key], n=1, cutoff=0.75):
                return f"; found '{key}'"
        return ""

    def _behavior(self, node: YNode) -> BehaviorDescriptor | None:
        name = self._required_name(node, "behavior", "a behavior descriptor")
        if name is None:
            return None
        self.check_keys(node, BEHAVIOR_TAGS, f"behavior {name}", name)
        marks: dict[str, Mark] = dict(node.key_marks)
        recurrent = self._recurrent_of(node, name)
        timeout: float | None
        if (t := node.get("timeout")) is not None:
            timeout = self.seconds(t, f"{name}: timeout", name)
        elif recurrent:
            timeout = None  # recurrent behaviors run until inhibited: nothing to default
        elif self.default_timeout is not None:
            timeout = self.default_timeout
        else:
            timeout = DEFAULT_TIMEOUT_S
            if self.default_recurrent is None:
                self.report(
                    codes.MISSING_WARNING_TAG,
                    Severity.WARNING,
                    f"{name}: no timeout; the default {DEFAULT_TIMEOUT_S:g} s is applied",
                    node.mark,
                    name,
                )
        lists = self.names(
            self.dependency(node, "incompatible_lists", name, name),
            f"{name}: incompatible_lists",
            name,
        )
        caps = self.names(
            self.dependency(node, "capabilities", name, name), f"{name}: capabilities", name
        )
        arguments = self._arguments(self.dependency(node, "arguments", name, name), name, marks)
        items = {
            "incompatible_lists": lists.marks,
            "capabilities": caps.marks,
        }
        return BehaviorDescriptor(
            name=name,
            timeout=timeout,
            recurrent=bool(recurrent),
            incompatible_lists=lists.names,
            capabilities=caps.names,
            arguments=arguments,
            mark=node.mark,
            marks=Marks(marks, items),
        )

    def _recurrent_of(self, node: YNode, name: str) -> bool:
        if (r := node.get("recurrent")) is not None:
            self.saw_thesis_tags = True
            return bool(self.boolean(r, f"{name}: recurrent", name))
        if (c := node.get("category")) is not None:
            self.saw_flown_tags = True
            return bool(self.category(c, name))
        if self.default_recurrent is not None:
            return self.default_recurrent
        self.report(
            codes.MISSING_WARNING_TAG,
            Severity.WARNING,
            f"{name}: neither recurrent nor category is set; goal-based is applied",
            node.mark,
            name,
        )
        return False

    def _arguments(
        self, node: YNode | None, behavior: str, marks: dict[str, Mark]
    ) -> tuple[ArgumentSpec, ...]:
        if node is None or node.value is None:
            return ()
        if not node.is_list:
            self.error(
                codes.WRONG_TYPE,
                f"{behavior}: arguments must be a list, got {_kind(node)}",
                node.mark,
                behavior,
            )
            return ()
        specs: list[ArgumentSpec] = []
        for item in node.value:
            if not item.is_map:
                self.error(
                    codes.WRONG_TYPE,
                    f"{behavior}: each argument must be a mapping, got {_kind(item)}",
                    item.mark,
                    behavior,
                )
                continue
            name = self._required_name(item, "argument", f"an argument of {behavior}", behavior)
            if name is None:
                continue
            self.check_keys(item, ARGUMENT_TAGS, f"argument {behavior}.{name}", behavior)
            marks[f"arguments.{name}"] = item.mark
            specs.append(self._argument_spec(item, behavior, name))
        return tuple(specs)

    def _argument_spec(self, node: YNode, behavior: str, name: str) -> ArgumentSpec:
        def malformed(message: str, mark: Mark) -> ArgumentSpec:
            self.error(
                codes.MALFORMED_ARGUMENT, f"{behavior}: argument {name}: {message}", mark, behavior
            )
            return ArgumentSpec(name, ArgumentKind.INVALID, mark=node.mark)

        dimensions = 1
        if (dims := node.get("dimensions")) is not None:
            if not isinstance(dims.value, int) or isinstance(dims.value, bool) or dims.value < 1:
                return malformed(
                    f"dimensions must be a whole number >= 1, got {_kind(dims)}", dims.mark
                )
            dimensions = dims.value
        allowed = node.get("allowed_values")
        if allowed is None:
            return malformed("no allowed_values", node.mark)
        if allowed.value == "TEXT":
            return ArgumentSpec(name, ArgumentKind.TEXT, dimensions=dimensions, mark=node.mark)
        if not allowed.is_list or not allowed.value:
            return malformed(
                "allowed_values must be [min, max], a list of symbols or TEXT, "
                f"got {_kind(allowed)}",
                allowed.mark,
            )
        values = [v.text for v in allowed.value]
        if all(_is_number(v) for v in values):
            if len(values) != 2:
                return malformed(
                    f"a numeric range is [min, max], got {len(values)} numbers", allowed.mark
                )
            low, high = as_float(values[0]), as_float(values[1])
            if low is None or high is None:
                return malformed("a range bound is NaN or too large for a float", allowed.mark)
            if low > high:
                return malformed(
                    f"empty range [{values[0]}, {values[1]}] (min > max)", allowed.mark
                )
            return ArgumentSpec(name, ArgumentKind.RANGE, low, high, dimensions, mark=node.mark)
        if all(isinstance(v, str) and v for v in values):
            if len(set(values)) != len(values):
                return malformed("a symbol is listed twice", allowed.mark)
            if dimensions != 1:
                return malformed("dimensions applies only to numeric ranges", node.mark)
            return ArgumentSpec(name, ArgumentKind.SYMBOLS, symbols=tuple(values), mark=node.mark)
        return malformed("allowed_values mixes numbers and symbols", allowed.mark)

    def _list(self, node: YNode) -> BehaviorList | None:
        name = self._required_name(node, "list", "a behavior list")
        if name is None:
            return None
        self.check_keys(node, LIST_TAGS, f"list {name}", name)
        members_node = node.get("behaviors")
        if members_node is None:
            self.error(
                codes.MISSING_ERROR_TAG,
                f"list {name} has no 'behaviors' (an error tag)",
                node.mark,
                name,
            )
            return None
        members = self.names(members_node, f"list {name}: behaviors", name)
        marks = Marks(node.key_marks, {"behaviors": members.marks})
        return BehaviorList(name, members.names, node.mark, marks)

    def _capability(self, node: YNode) -> CapabilityDescriptor | None:
        name = self._required_name(node, "capability", "a capability descriptor")
        if name is None:
            return None
        self.check_keys(node, CAPABILITY_TAGS, f"capability {name}", name)
        processes_node = node.get("processes")
        if processes_node is not None:
            self.saw_thesis_tags = True
        elif (processes_node := node.get("process_sequence")) is not None:
            self.saw_flown_tags = True
        else:
            self.error(
                codes.MISSING_ERROR_TAG,
                f"capability {name} has no 'processes' (an error tag)",
                node.mark,
                name,
            )
            return None
        processes = self.names(processes_node, f"capability {name}: processes", name)
        default = self._active_by_default(node, name)
        conflicts = self.names(
            self.dependency(node, "incompatible_capabilities", f"capability {name}", name),
            f"capability {name}: incompatible_capabilities",
            name,
        )
        required = self.names(
            node.get("required_capabilities"), f"capability {name}: required_capabilities", name
        )
        marks = Marks(
            node.key_marks,
            {
                key: refs.marks
                for key, refs in (
                    ("processes", processes),
                    ("incompatible_capabilities", conflicts),
                    ("required_capabilities", required),
                )
            },
        )
        return CapabilityDescriptor(
            name=name,
            processes=processes.names,
            active_by_default=default,
            incompatible_capabilities=conflicts.names,
            required_capabilities=required.names,
            mark=node.mark,
            marks=marks,
        )

    def _active_by_default(self, node: YNode, name: str) -> bool:
        value = self.tag(node, "active_by_default")
        if value is not None:
            self.saw_thesis_tags = True
            return bool(self.boolean(value, f"capability {name}: active_by_default", name))
        if not self.saw_flown_tags:
            # The 2.x format has no such tag; in the thesis format it is a warning tag.
            self.report(
                codes.MISSING_WARNING_TAG,
                Severity.WARNING,
                f"capability {name}: no active_by_default; 'no' is applied",
                node.mark,
                name,
            )
        return False


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def as_float(value: Any) -> float | None:
    """A YAML number as a float; None for non-numbers, NaN (it compares false with
    everything, so every value would be "outside") and ints beyond float range."""
    if not _is_number(value):
        return None
    try:
        number = float(value)
    except OverflowError:
        return None
    return None if math.isnan(number) else number
