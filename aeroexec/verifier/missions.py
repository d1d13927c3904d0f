"""AX7xx: static checks of mission scripts against a catalog.

A mission script is read with `ast` and never executed. Every call of the mission API
— `execute_behavior`, `activate_behavior`, `inhibit_behavior` and the thesis'
camelCase `executeBehavior`, `activateBehavior`, `inhibitBehavior`, called bare or as
an attribute (`api.executeBehavior(...)`) — whose behavior name is a string literal is
checked: the behavior exists; each keyword argument exists and its literal value has
the right type, range and number of dimensions (elements that are not literals, like
`coordinates=[x, y, z]`, still count for the dimension check); `execute_behavior` is
not given a recurrent behavior; a behavior that is inhibited is activated somewhere.
"""

from __future__ import annotations

import ast
import glob
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from aeroexec.catalog.arguments import check_value
from aeroexec.catalog.model import ArgumentKind, ArgumentSpec, Catalog, Severity
from aeroexec.errors import Mark, MissionError
from aeroexec.verifier.findings import Finding
from aeroexec.verifier.registry import mission_rule
from aeroexec.verifier.suggest import Suggester

E, W = Severity.ERROR, Severity.WARNING

#: Mission API functions -> what they do.
MISSION_CALLS = {
    "execute_behavior": "execute",
    "executeBehavior": "execute",
    "activate_behavior": "activate",
    "activateBehavior": "activate",
    "inhibit_behavior": "inhibit",
    "inhibitBehavior": "inhibit",
}

UNKNOWN_BEHAVIOR = mission_rule(
    "AX701",
    "mission-unknown-behavior",
    E,
    """A mission calls `execute_behavior`/`activate_behavior`/`inhibit_behavior` with a
    behavior the catalog does not define (the thesis' Appendix C mission activates
    `PAY_ATTENTION_TO_VISUAL_MARKERS`, which its Appendix A catalog calls
    `PAY_ATTENTION`). In flight: the call is rejected and the mission goes on without
    it. Fix: use the catalog's name (the message suggests the closest one) or add the
    behavior to the catalog.""",
).code
UNKNOWN_ARGUMENT = mission_rule(
    "AX702",
    "mission-unknown-argument",
    E,
    """A mission passes an argument the behavior does not declare (names are compared
    ignoring case), passes one twice, or passes arguments by position instead of by
    keyword. In flight: the behavior specialist's format check rejects the
    activation. Fix: use a declared argument name, as `name=value`.""",
).code
BAD_VALUE = mission_rule(
    "AX703",
    "mission-bad-argument-value",
    E,
    """A mission passes a literal argument value outside the declared range, not among
    the declared symbols, or of the wrong type (text where numbers are expected...).
    In flight: the format check rejects the activation. Fix: pass a value the catalog
    allows, or widen `allowed_values`.""",
).code
WRONG_DIMENSIONS = mission_rule(
    "AX704",
    "mission-wrong-dimensions",
    E,
    """A mission passes a vector with a different number of values than the argument's
    `dimensions` (e.g. two coordinates for a 3-dimensional point), or a single number
    where a vector is declared. In flight: the format check rejects the activation.
    Fix: pass exactly `dimensions` values.""",
).code
EXECUTE_RECURRENT = mission_rule(
    "AX705",
    "mission-execute-recurrent",
    E,
    """A mission uses `execute_behavior` (activate and wait for the end event) on a
    recurrent behavior. Recurrent behaviors never end by themselves. In flight: the
    2017 API blocks the mission forever; aeroexec's mission API refuses the call at
    once. Fix: `activate_behavior` it, and `inhibit_behavior` it when it is no longer
    needed.""",
).code
INHIBIT_NOT_ACTIVATED = mission_rule(
    "AX706",
    "mission-inhibit-never-activated",
    W,
    """A mission inhibits a behavior that it never activates with `activate_behavior`
    (a behavior run with `execute_behavior` has already ended when that call returns).
    In flight: the inhibition is rejected ("not active"). The check is per file and
    ignores control flow. Fix: inhibit what the mission activated, or remove the
    call.""",
).code


class _Unknown:
    """A value the verifier cannot know without running the mission."""

    def __repr__(self) -> str:
        return "<not a literal>"


UNKNOWN: Any = _Unknown()


@dataclass(frozen=True, slots=True)
class CallArgument:
    name: str
    value: Any  # a literal, UNKNOWN, or a list that may contain UNKNOWN
    mark: Mark


@dataclass(frozen=True, slots=True)
class MissionCall:
    kind: str  # "execute" | "activate" | "inhibit"
    function: str  # as written: executeBehavior, inhibit_behavior...
    behavior: str | None  # None when the name is not a string literal
    arguments: tuple[CallArgument, ...]
    positional: tuple[Mark, ...]  # extra positional arguments after the name
    mark: Mark
    name_mark: Mark


@dataclass(frozen=True, slots=True)
class MissionScript:
    path: str
    calls: tuple[MissionCall, ...]


# -- reading -----------------------------------------------------------------------------
def expand_mission_paths(patterns: Iterable[str | Path]) -> list[str]:
    """Files named by paths and glob patterns (`**` recursive), each once, in order.
    `MissionError` for a pattern that names nothing."""
    found: dict[str, None] = {}
    for pattern in patterns:
        text = str(pattern)
        path = Path(text)
        try:
            is_file, is_dir = path.is_file(), path.is_dir()
        except OSError as exc:  # e.g. a name too long
            raise MissionError(f"cannot read: {exc.strerror}", Mark(text)) from None
        if is_file:
            found[text] = None
            continue
        if is_dir:
            raise MissionError("is a directory; give mission files or a glob", Mark(text))
        if glob.has_magic(text):
            matches = sorted(m for m in glob.glob(text, recursive=True) if Path(m).is_file())
            if matches:
                found.update(dict.fromkeys(matches))
                continue
            raise MissionError("no mission file matches this pattern", Mark(text))
        raise MissionError("no such file", Mark(text))
    return list(found)


def read_mission(path: str | Path) -> MissionScript:
    file = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise MissionError("no such file", Mark(file)) from None
    except IsADirectoryError:
        raise MissionError("is a directory, not a mission script", Mark(file)) from None
    except UnicodeDecodeError as exc:
        raise MissionError(f"not UTF-8 text (byte {exc.start})", Mark(file)) from None
    except OSError as exc:
        raise MissionError(f"cannot read: {exc.strerror}", Mark(file)) from None
    return parse_mission(text, file)


def parse_mission(text: str, file: str = "<mission>") -> MissionScript:
    """Parse (never run) a mission script; `MissionError` with file:line:col when it is
    not valid Python."""
    try:
        tree = ast.parse(text, filename=file)
    except SyntaxError as exc:
        line = exc.lineno or 0
        column = exc.offset or 0
        raise MissionError(f"not valid Python: {exc.msg}", Mark(file, line, column)) from None
    except ValueError as exc:  # e.g. NUL bytes
        raise MissionError(f"cannot parse: {exc}", Mark(file)) from None
    lines = text.splitlines()
    calls = tuple(_calls(tree, file, lines))
    return MissionScript(file, calls)


def _mark(file: str, lines: Sequence[str], node: ast.expr | ast.keyword) -> Mark:
    """1-based line and character column (ast counts UTF-8 bytes)."""
    line = node.lineno
    offset = node.col_offset
    if 0 < line <= len(lines):
        prefix = lines[line - 1].encode("utf-8")[:offset]
        offset = len(prefix.decode("utf-8", errors="replace"))
    return Mark(file, line, offset + 1)


def _function_name(func: ast.expr) -> str | None:
    if isinstance(func, ast.Name):
        return func.id
    if isinstance(func, ast.Attribute):
        return func.attr
    return None


def _calls(tree: ast.AST, file: str, lines: Sequence[str]) -> Iterator[MissionCall]:
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        function = _function_name(node.func)
        if function not in MISSION_CALLS:
            continue
        found.append(_call(node, function, file, lines))
    found.sort(key=lambda c: (c.mark.line, c.mark.column))
    yield from found


def _call(node: ast.Call, function: str, file: str, lines: Sequence[str]) -> MissionCall:
    mark = _mark(file, lines, node)
    behavior: str | None = None
    name_mark = mark
    positional: list[Mark] = []
    args = list(node.args)
    if args and not isinstance(args[0], ast.Starred):
        first = args.pop(0)
        name_mark = _mark(file, lines, first)
        if isinstance(first, ast.Constant) and isinstance(first.value, str):
            behavior = first.value
    positional.extend(_mark(file, lines, a) for a in args)
    arguments: list[CallArgument] = []
    for keyword in node.keywords:
        if keyword.arg is None:
            # **{'angle': 90} with a literal dict is checked like keywords.
            if isinstance(keyword.value, ast.Dict):
                for key, value in zip(keyword.value.keys, keyword.value.values, strict=True):
                    if isinstance(key, ast.Constant) and isinstance(key.value, str):
                        arguments.append(
                            CallArgument(key.value, _literal(value), _mark(file, lines, key))
                        )
            continue
        if keyword.arg in ("name", "behavior") and behavior is None and not node.args:
            if isinstance(keyword.value, ast.Constant) and isinstance(keyword.value.value, str):
                behavior = keyword.value.value
                name_mark = _mark(file, lines, keyword.value)
            continue
        arguments.append(
            CallArgument(keyword.arg, _literal(keyword.value), _mark(file, lines, keyword))
        )
    return MissionCall(
        MISSION_CALLS[function],
        function,
        behavior,
        tuple(arguments),
        tuple(positional),
        mark,
        name_mark,
    )


def _literal(node: ast.expr) -> Any:
    if isinstance(node, ast.Constant):
        if isinstance(node.value, (str, int, float, bool)) or node.value is None:
            return node.value
        return UNKNOWN
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        inner = _literal(node.operand)
        if isinstance(inner, (int, float)) and not isinstance(inner, bool):
            return -inner if isinstance(node.op, ast.USub) else inner
        return UNKNOWN
    if isinstance(node, (ast.List, ast.Tuple)):
        if any(isinstance(e, ast.Starred) for e in node.elts):
            return UNKNOWN
        return [_literal(e) for e in node.elts]
    return UNKNOWN


# -- checking ----------------------------------------------------------------------------
def _contains_unknown(value: Any) -> bool:
    if value is UNKNOWN:
        return True
    return isinstance(value, list) and any(_contains_unknown(v) for v in value)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


class MissionChecker:
    """Checks mission scripts against one catalog."""

    def __init__(self, catalog: Catalog, note: str = "") -> None:
        self.catalog = catalog
        self.note = note
        self.names = Suggester(catalog.behaviors)

    def check(self, script: MissionScript) -> list[Finding]:
        findings: list[Finding] = []
        activated = {c.behavior for c in script.calls if c.kind == "activate"}
        executed = {c.behavior for c in script.calls if c.kind == "execute"}
        for call in script.calls:
            findings.extend(self._check_call(call, activated, executed))
        return findings

    def _finding(
        self, rule: str, severity: Severity, message: str, mark: Mark, *subjects: str
    ) -> Finding:
        return Finding.at(rule, severity, message + self.note, mark, subjects)

    def _check_call(
        self, call: MissionCall, activated: set[str | None], executed: set[str | None]
    ) -> Iterator[Finding]:
        name = call.behavior
        if name is None:
            return
        shown = f"{call.function}('{name}')"
        descriptor = self.catalog.behaviors.get(name)
        if descriptor is None:
            yield self._finding(
                UNKNOWN_BEHAVIOR,
                E,
                f"{shown}: unknown behavior {name}{self.names.hint(name)}",
                call.name_mark,
                name,
            )
            return
        if call.kind == "execute" and descriptor.recurrent:
            yield self._finding(
                EXECUTE_RECURRENT,
                E,
                f"{shown} would never return: {name} is recurrent (activate it, then inhibit it)",
                call.mark,
                name,
            )
        if call.kind == "inhibit":
            if name not in activated:
                why = (
                    "it is only executed, and has ended when execute returns"
                    if name in executed
                    else "it is never activated in this mission"
                )
                yield self._finding(INHIBIT_NOT_ACTIVATED, W, f"{shown}: {why}", call.mark, name)
            return
        for mark in call.positional:
            yield self._finding(
                UNKNOWN_ARGUMENT,
                E,
                f"{shown}: arguments are passed by keyword (name=value), not by position",
                mark,
                name,
            )
        seen: dict[str, str] = {}
        for argument in call.arguments:
            spec = descriptor.argument(argument.name)
            if spec is None:
                declared = [s.name for s in descriptor.arguments]
                hint = Suggester(declared).hint(argument.name)
                known = ", ".join(declared) or "none"
                yield self._finding(
                    UNKNOWN_ARGUMENT,
                    E,
                    f"{shown}: unknown argument '{argument.name}'{hint} (arguments: {known})",
                    argument.mark,
                    name,
                    argument.name,
                )
                continue
            if spec.name in seen:
                yield self._finding(
                    UNKNOWN_ARGUMENT,
                    E,
                    f"{shown}: {spec.name} is given twice ('{seen[spec.name]}' and "
                    f"'{argument.name}')",
                    argument.mark,
                    name,
                    spec.name,
                )
                continue
            seen[spec.name] = argument.name
            yield from self._check_value(shown, name, spec, argument)

    def _check_value(
        self, shown: str, behavior: str, spec: ArgumentSpec, argument: CallArgument
    ) -> Iterator[Finding]:
        value = argument.value
        if value is UNKNOWN or spec.kind is ArgumentKind.INVALID:
            return
        subjects = (behavior, spec.name)
        if spec.kind is ArgumentKind.RANGE:
            if isinstance(value, list) and len(value) != spec.dimensions:
                got = f"{len(value)} value{'s' if len(value) != 1 else ''}"
                yield self._finding(
                    WRONG_DIMENSIONS,
                    E,
                    f"{shown}: {spec.name} needs {spec.describe()}, got {got}",
                    argument.mark,
                    *subjects,
                )
                return
            if spec.dimensions > 1 and _is_number(value):
                yield self._finding(
                    WRONG_DIMENSIONS,
                    E,
                    f"{shown}: {spec.name} needs {spec.describe()}, got a single number",
                    argument.mark,
                    *subjects,
                )
                return
            if isinstance(value, list) and _contains_unknown(value):
                known = [v for v in value if v is not UNKNOWN]
                single = ArgumentSpec(spec.name, spec.kind, spec.minimum, spec.maximum)
                for element in known:
                    error, _ = check_value(behavior, single, element)
                    if error:
                        yield self._finding(
                            BAD_VALUE,
                            E,
                            f"{shown}: {spec.name} needs {spec.describe()}, got "
                            f"{_show(value)} ({_show(element)} is not allowed)",
                            argument.mark,
                            *subjects,
                        )
                        return
                return
        elif _contains_unknown(value):
            return
        error, _ = check_value(behavior, spec, value)
        if error:
            yield self._finding(
                BAD_VALUE, E, f"{shown}: {error.split(': ', 1)[-1]}", argument.mark, *subjects
            )


def _show(value: Any) -> str:
    if isinstance(value, list):
        return "[" + ", ".join(_show(v) for v in value) + "]"
    if value is UNKNOWN:
        return "?"
    return repr(value)


def check_mission(script: MissionScript, catalog: Catalog, note: str = "") -> list[Finding]:
    """Findings (AX7xx) for one mission script against one catalog."""
    return MissionChecker(catalog, note).check(script)
