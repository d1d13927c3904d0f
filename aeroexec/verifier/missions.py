"""AX7xx: static checks of mission scripts against a catalog.

A mission script is read with `ast` and never executed. `mission_fold` folds it into
the mission API calls it makes — `execute_behavior`, `activate_behavior`,
`inhibit_behavior` and the thesis' camelCase `executeBehavior`, `activateBehavior`,
`inhibitBehavior`, called bare, as an attribute (`api.executeBehavior(...)`), through
an alias, from a helper function or in a loop over names — with every argument folded
to a constant where it is one. Each call whose behavior name is known is checked: the
behavior exists; each keyword argument exists and its known value has the right type,
range and number of dimensions (elements that are not known, like `coordinates=[x, y,
z]`, still count for the dimension check); `execute_behavior` is not given a recurrent
behavior; a behavior that is inhibited is activated somewhere. Calls whose behavior
name stays unknown are counted (AX708); a script without an entry point is an error
(AX707). `mission_run` then runs the calls as a sequence (AX709-AX715).
"""

from __future__ import annotations

import ast
import io
import os
import tokenize
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from aeroexec.catalog.arguments import check_value
from aeroexec.catalog.model import ArgumentKind, ArgumentSpec, Catalog, Severity
from aeroexec.errors import Mark, MissionError
from aeroexec.executive.behavior import Behavior
from aeroexec.inputs import glob_files, has_magic, read_text
from aeroexec.vehicles.world import World
from aeroexec.verifier.findings import Finding
from aeroexec.verifier.mission_fold import (
    ENTRY_POINTS,
    MISSION_CALLS,
    UNKNOWN,
    CallArgument,
    FoldedMission,
    MissionCall,
    fold_mission,
)
from aeroexec.verifier.mission_run import MissionRun, called_from
from aeroexec.verifier.registry import mission_rule
from aeroexec.verifier.suggest import Suggester

E, W, INFO = Severity.ERROR, Severity.WARNING, Severity.INFO

__all__ = [
    "MISSION_CALLS",
    "UNKNOWN",
    "CallArgument",
    "MissionCall",
    "MissionScript",
    "check_mission",
    "parse_mission",
    "read_mission",
]

UNKNOWN_BEHAVIOR = mission_rule(
    "AX701",
    "mission-unknown-behavior",
    E,
    """A mission calls `execute_behavior`/`activate_behavior`/`inhibit_behavior` with a
    behavior the catalog does not define (the thesis' Appendix C mission activates
    `PAY_ATTENTION_TO_VISUAL_MARKERS`, which its Appendix A catalog calls
    `PAY_ATTENTION`). In flight: the call is rejected and the mission goes on without
    it. A node of a behavior-tree mission naming a task the task catalog lacks (or that
    no behavior performs) is reported the same way. Fix: use the catalog's name (the
    message suggests the closest one) or add the behavior to the catalog.""",
).code
UNKNOWN_ARGUMENT = mission_rule(
    "AX702",
    "mission-unknown-argument",
    E,
    """A mission passes an argument the behavior does not declare (names are compared
    ignoring case), passes one twice, or passes arguments by position instead of by
    keyword. In flight: the behavior specialist's format check rejects the
    activation. In a behavior-tree mission: a node's parameter the task does not declare.
    Fix: use a declared argument name, as `name=value`.""",
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


NO_ENTRY_POINT = mission_rule(
    "AX707",
    "mission-no-entry-point",
    E,
    """The script defines none of `runMission()`, `run_mission()` or `main()`. Aerostack
    called `runMission()`; `aeroexec run` calls the first of those it finds after
    running the module's top level. In flight: nothing of the mission runs (aeroexec
    refuses the script; Aerostack's interpreter failed on the missing function). Fix:
    define `runMission()` and put the mission in it.""",
).code
NOT_CHECKED = mission_rule(
    "AX708",
    "mission-calls-not-checked",
    INFO,
    """Mission calls whose behavior name the verifier cannot know before the mission
    runs (read from a belief, built from data, passed through `*args`). Constants are
    folded first — a name in a variable or in a dict nothing changes (`NAMES['up']`), a
    loop over a literal list of names or a constant `range(n)`, a helper function called
    with constant arguments, an alias of the API — so what is left
    really depends on the run. In flight: these calls are checked by the executive
    only, when they happen. Reported once per mission with the lines. Fix: nothing
    needed; name the behavior literally where you can, to have it checked before
    flight.""",
).code


@dataclass(frozen=True, slots=True)
class MissionScript:
    path: str
    folded: FoldedMission

    @property
    def calls(self) -> tuple[MissionCall, ...]:
        return self.folded.calls


# -- reading -----------------------------------------------------------------------------
def expand_mission_paths(patterns: Iterable[str | Path]) -> tuple[list[str], list[MissionError]]:
    """Files named by paths and glob patterns (`**` recursive), each once, in order, and
    the errors met: a pattern that names nothing, a directory the search could not read,
    a match that is a symlink loop (`aeroexec.inputs.glob_files`). A plain path that
    names no file is left for `read_mission` to say why."""
    found: dict[str, None] = {}
    errors: list[MissionError] = []
    for pattern in patterns:
        text = str(pattern)
        try:
            is_dir = Path(text).is_dir()
        except OSError as exc:  # e.g. a name too long
            errors.append(MissionError(f"cannot read: {exc.strerror}", Mark(text)))
            continue
        if is_dir:
            errors.append(MissionError("is a directory; give mission files or a glob", Mark(text)))
        elif not has_magic(text) or os.path.lexists(text):
            found[text] = None  # read_mission refuses a missing or non-regular one
        else:
            matches = glob_files(text)
            errors.extend(MissionError(u.problem, Mark(u.path)) for u in matches.unreadable)
            if not matches.files and not matches.unreadable:
                errors.append(MissionError("no mission file matches this pattern", Mark(text)))
            found.update(dict.fromkeys(matches.files))
    return list(found), errors


def read_mission(path: str | Path) -> MissionScript:
    return parse_mission(read_text(path, "a mission script", MissionError), str(path))


def parse_mission(text: str, file: str = "<mission>") -> MissionScript:
    """Parse (never run) a mission script; `MissionError` with file:line:col when it is
    not valid Python, or nested too deeply for Python's own parser."""
    try:
        tree = ast.parse(text, filename=file)
    except SyntaxError as exc:
        line = exc.lineno or 0
        column = exc.offset or 0
        raise MissionError(f"not valid Python: {exc.msg}", Mark(file, line, column)) from None
    except ValueError as exc:  # e.g. NUL bytes
        raise MissionError(f"cannot parse: {exc}", Mark(file)) from None
    except (RecursionError, MemoryError):
        # CPython's parser gives up on a few thousand nested operators (RecursionError
        # "during ast construction", or MemoryError from its own stack): Python could
        # not run the script either.
        raise MissionError(
            "nested too deeply for Python's parser (an expression thousands of levels "
            "deep); Python cannot compile it",
            _deepest_line(text, file),
        ) from None
    return MissionScript(file, fold_mission(tree, file, text.splitlines()))


def _deepest_line(text: str, file: str) -> Mark:
    """The line with the most tokens: where a deep expression sits (tokenizing is flat,
    it needs no recursion)."""
    counts: dict[int, int] = {}
    try:
        for token in tokenize.generate_tokens(io.StringIO(text).readline):
            counts[token.start[0]] = counts.get(token.start[0], 0) + 1
    except (tokenize.TokenError, SyntaxError):
        pass
    if not counts:
        return Mark(file)
    line = max(counts, key=lambda n: (counts[n], -n))
    return Mark(file, line, 1)


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
            notes = called_from(call.via)
            findings.extend(
                replace(f, related=notes) for f in self._check_call(call, activated, executed)
            )
        if script.folded.entry is None:
            findings.append(
                self._finding(
                    NO_ENTRY_POINT,
                    E,
                    "the script defines none of "
                    + ", ".join(f"{name}()" for name in ENTRY_POINTS)
                    + ": no mission runs",
                    Mark(script.path, 1, 1),
                    script.path,
                )
            )
        unchecked = script.folded.unchecked
        if unchecked:
            lines = ", ".join(str(m.line) for m in unchecked)
            plural = "s" if len(unchecked) > 1 else ""
            findings.append(
                self._finding(
                    NOT_CHECKED,
                    INFO,
                    f"{len(unchecked)} call{plural} not checked: the behavior name is only "
                    f"known when the mission runs (line{plural} {lines})",
                    unchecked[0],
                    *(f"line {m.line}" for m in unchecked),
                )
            )
        # A call site reached with the same values twice (two callers of a helper) says
        # the same thing once, with the first call path.
        first: dict[Finding, Finding] = {}
        for finding in findings:
            first.setdefault(replace(finding, related=()), finding)
        return list(first.values())

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


def check_mission(
    script: MissionScript,
    catalog: Catalog,
    note: str = "",
    *,
    library: Mapping[str, type[Behavior]] | None = None,
    world: World | None = None,
) -> list[Finding]:
    """Findings (AX7xx) for one mission script against one catalog: each call, then the
    calls as sequences (`mission_run`), with the behaviors' declared situations from
    `library` (default: the standard library) and the vehicle limits of `world`
    (default: the built-in world)."""
    findings = MissionChecker(catalog, note).check(script)
    findings += MissionRun(catalog, note, library, world).run(script.folded, script.path)
    return findings
