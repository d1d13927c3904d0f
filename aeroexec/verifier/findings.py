"""What the verifier says: findings (frozen), their witnesses, and the report of a run."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from enum import Enum
from typing import Any

from aeroexec.catalog.model import Diagnostic, Severity
from aeroexec.errors import AeroexecError, Mark, one_line

__all__ = [
    "Finding",
    "InputError",
    "Outcome",
    "PathStep",
    "Related",
    "Report",
    "Severity",
    "Step",
    "Witness",
]


@dataclass(frozen=True, slots=True)
class Step:
    """One request of a witness: `activate_behavior(name, arguments)`, or for a task
    catalog `start_task(name, arguments)` (`service` "start_task")."""

    activate: str
    arguments: tuple[tuple[str, Any], ...] = ()
    service: str = "activate"

    def to_dict(self) -> dict[str, Any]:
        return {self.service: self.activate, "arguments": dict(self.arguments)}

    def call(self) -> str:
        """The behavior (or task) with its arguments: `GO_TO_POINT(COORDINATES=[1, 2, 3])`."""
        if not self.arguments:
            return self.activate
        shown = ", ".join(f"{name}={value!r}" for name, value in self.arguments)
        return f"{self.activate}({shown})"

    def describe(self) -> str:
        verb = "start task" if self.service == "start_task" else "activate"
        return f"{verb} {self.call()}"


class Outcome(str, Enum):
    """What the executive does when a witness is replayed."""

    #: Initiation (starting the default capabilities) fails; no activation is needed.
    INITIATION_FAILS = "initiation-fails"
    #: Every step but the last is accepted; the last activation is rejected.
    REJECTED = "rejected"
    #: Every step is accepted and every behavior named in the steps is still active.
    ALL_ACTIVE = "all-active"


@dataclass(frozen=True, slots=True)
class Witness:
    """The shortest activation sequence (from a freshly initiated executive) that makes a
    finding's problem happen, and what happens then."""

    steps: tuple[Step, ...]
    outcome: Outcome
    #: Behaviors run to their end first, so that the steps' situations hold for the
    #: real behaviors (TAKE_OFF before a motion behavior); see `witness_run`.
    setup: tuple[Step, ...] = ()
    #: Why the real behaviors could not reproduce it, when they could not (then the
    #: witness holds with stand-in behaviors only).
    caveat: str = ""

    def to_list(self) -> list[dict[str, Any]]:
        setup = [{**step.to_dict(), "until_end": True} for step in self.setup]
        return setup + [step.to_dict() for step in self.steps]

    def describe(self) -> str:
        caveat = f" ({self.caveat})" if self.caveat else ""
        if self.outcome is Outcome.INITIATION_FAILS:
            return f"initiation fails before any activation{caveat}"
        names = [s.activate for s in self.steps]
        prefix = "".join(f"run {s.call()} to its end, then " for s in self.setup)
        sequence = prefix + ", then ".join(step.describe() for step in self.steps)
        if self.outcome is Outcome.REJECTED:
            request = "start" if self.steps[-1].service == "start_task" else "activation"
            return f"{sequence}: the {request} of {names[-1]} is rejected{caveat}"
        return f"{sequence}: all of {', '.join(dict.fromkeys(names))} stay active{caveat}"


@dataclass(frozen=True, slots=True)
class PathStep:
    """One step of the way through a mission that leads to a finding: a mission call
    (`execute`, `activate`, `inhibit`) or a decision (`branch`, `loop`, `return`)."""

    line: int
    column: int
    action: str
    detail: str = ""

    def describe(self) -> str:
        return f"{self.line}: {self.action}{' ' + self.detail if self.detail else ''}"

    def to_dict(self) -> dict[str, Any]:
        return {
            "line": self.line,
            "column": self.column,
            "action": self.action,
            "detail": self.detail,
        }


@dataclass(frozen=True, slots=True)
class Related:
    """Another place a finding leads through, as a compiler's note: the call of the
    helper a mission finding sits in ("in fly(), called from here")."""

    file: str
    line: int
    column: int
    message: str

    @classmethod
    def called_from(cls, helper: str, mark: Mark) -> Related:
        return cls(
            mark.file, max(mark.line, 0), max(mark.column, 0), f"in {helper}(), called from here"
        )

    @property
    def location(self) -> str:
        return str(Mark(self.file, self.line, self.column))

    def to_dict(self) -> dict[str, Any]:
        return {
            "file": self.file,
            "line": self.line,
            "column": self.column,
            "message": self.message,
        }


@dataclass(frozen=True, slots=True)
class InputError:
    """An input the verifier could not read; the other inputs are still verified."""

    message: str
    file: str
    line: int = 0
    column: int = 0

    @classmethod
    def of(cls, error: AeroexecError, file: str = "") -> InputError:
        mark = error.mark or Mark(file)
        return cls(error.message, mark.file, max(mark.line, 0), max(mark.column, 0))

    @property
    def mark(self) -> Mark:
        return Mark(self.file, self.line, self.column)

    def __str__(self) -> str:
        where = str(self.mark) if self.file else "aeroexec"
        return one_line(f"{where}: error: {self.message}")

    def to_dict(self) -> dict[str, Any]:
        return {
            "message": self.message,
            "file": self.file,
            "line": self.line,
            "column": self.column,
        }


@dataclass(frozen=True, slots=True)
class Finding:
    """One problem at one place. `line`/`column` are 1-based; 0 when unknown."""

    rule: str
    severity: Severity
    message: str
    file: str
    line: int = 0
    column: int = 0
    subjects: tuple[str, ...] = ()
    witness: Witness | None = None
    #: For mission findings: the way through the mission that leads here.
    path: tuple[PathStep, ...] = ()
    #: Where the helper calls leading here are, innermost first (compiler notes).
    related: tuple[Related, ...] = ()

    @classmethod
    def at(
        cls,
        rule: str,
        severity: Severity,
        message: str,
        mark: Mark,
        subjects: Iterable[str] = (),
        witness: Witness | None = None,
        path: tuple[PathStep, ...] = (),
        related: tuple[Related, ...] = (),
    ) -> Finding:
        return cls(
            rule,
            severity,
            message,
            mark.file,
            max(mark.line, 0),
            max(mark.column, 0),
            tuple(dict.fromkeys(subjects)),
            witness,
            path,
            related,
        )

    @classmethod
    def in_file(
        cls,
        file: str,
        rule: str,
        severity: Severity,
        message: str,
        mark: Mark,
        subjects: Iterable[str] = (),
        witness: Witness | None = None,
    ) -> Finding:
        """`at`, placed in `file` when the mark names none (a catalog parsed from memory
        carries marks without a file: its findings still belong to its source)."""
        if not mark.file or mark.file == "<memory>":
            mark = Mark(file, mark.line, mark.column)
        return cls.at(rule, severity, message, mark, subjects, witness)

    @classmethod
    def from_diagnostic(cls, diagnostic: Diagnostic) -> Finding:
        return cls.at(
            diagnostic.code,
            diagnostic.severity,
            diagnostic.message,
            diagnostic.mark,
            diagnostic.subjects,
        )

    @property
    def mark(self) -> Mark:
        return Mark(self.file, self.line, self.column)

    @property
    def location(self) -> str:
        return str(self.mark)

    def sort_key(self) -> tuple[str, int, int, str, str]:
        return (self.file, self.line, self.column, self.rule, self.message)

    def to_dict(self) -> dict[str, Any]:
        return {
            "rule": self.rule,
            "severity": self.severity.value,
            "message": self.message,
            "file": self.file,
            "line": self.line,
            "column": self.column,
            "subjects": list(self.subjects),
            "witness": None if self.witness is None else self.witness.to_list(),
            "path": [step.to_dict() for step in self.path],
            "related": [note.to_dict() for note in self.related],
        }

    def __str__(self) -> str:
        return f"{self.location}: {self.severity.value} {self.rule} {self.message}"


_RANK = {Severity.INFO: 0, Severity.WARNING: 1, Severity.ERROR: 2}


@dataclass(frozen=True, slots=True)
class Omitted:
    """Findings of one rule (and severity) beyond the report's limit: counted, not kept."""

    rule: str
    severity: Severity
    count: int

    def to_dict(self) -> dict[str, Any]:
        return {"rule": self.rule, "severity": self.severity.value, "count": self.count}


class FindingCollector:
    """Findings as rules yield them, keeping at most `limit` per rule (None: all): the
    first ones by place (`Finding.sort_key`), the rest only counted.

    A catalog with a million dangling names yields a million findings; nobody reads past
    the first screenful of one rule's, and holding them all costs hundreds of bytes
    each. Per rule, a buffer of at most `max(4 * limit, 4096)` findings is sorted and cut
    back to `limit` when full: memory bounded by the limit, time n log(buffer).
    """

    def __init__(
        self, limit: int | None = None, admit: Callable[[Finding], bool] | None = None
    ) -> None:
        if limit is not None and limit < 0:
            raise ValueError("limit must be >= 0 or None")
        self.limit = limit
        #: Which findings are taken at all (the rules selected, not suppressed in place).
        self.admit = admit
        self._room = 0 if limit is None else max(4 * limit, 4096)
        self._all: list[Finding] = []
        self._kept: dict[str, list[Finding]] = {}
        self._seen: dict[tuple[str, Severity], int] = {}

    def add(self, finding: Finding) -> None:
        if self.admit is not None and not self.admit(finding):
            return
        if self.limit is None:
            self._all.append(finding)
            return
        key = (finding.rule, finding.severity)
        self._seen[key] = self._seen.get(key, 0) + 1
        kept = self._kept.setdefault(finding.rule, [])
        kept.append(finding)
        if len(kept) >= self._room:
            kept.sort(key=Finding.sort_key)
            del kept[self.limit :]

    def extend(self, findings: Iterable[Finding]) -> None:
        for finding in findings:
            self.add(finding)

    def findings(self) -> tuple[Finding, ...]:
        """The findings kept (unsorted: `Report` sorts them)."""
        if self.limit is None:
            return tuple(self._all)
        out: list[Finding] = []
        for kept in self._kept.values():
            kept.sort(key=Finding.sort_key)
            del kept[self.limit :]
            out.extend(kept)
        return tuple(out)

    def omitted(self) -> tuple[Omitted, ...]:
        """What was counted but not kept, per rule and severity (rule order)."""
        if self.limit is None:
            return ()
        kept: dict[tuple[str, Severity], int] = {}
        for finding in self.findings():
            key = (finding.rule, finding.severity)
            kept[key] = kept.get(key, 0) + 1
        return tuple(
            Omitted(rule, severity, seen - kept.get((rule, severity), 0))
            for (rule, severity), seen in sorted(self._seen.items(), key=lambda i: i[0][0])
            if seen > kept.get((rule, severity), 0)
        )


@dataclass(frozen=True)
class Report:
    """Every finding of one verifier run, sorted by place, and the inputs it read."""

    findings: tuple[Finding, ...]
    catalogs: tuple[str, ...] = ()
    missions: tuple[str, ...] = ()
    #: Findings left out by `at_least` (below the severity asked for).
    hidden: int = 0
    #: Inputs that could not be read (the others were verified all the same).
    input_errors: tuple[InputError, ...] = ()
    #: Findings silenced by a comment in place (noqa, or aeroexec: ignore[...]).
    suppressed: int = 0
    #: Findings beyond the limit of findings kept per rule (`verify(max_findings=...)`):
    #: counted in the summary and the exit code, not listed.
    omitted: tuple[Omitted, ...] = ()
    _counts: Mapping[Severity, int] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        ordered = tuple(sorted(self.findings, key=Finding.sort_key))
        object.__setattr__(self, "findings", ordered)
        counts = dict.fromkeys(Severity, 0)
        for finding in ordered:
            counts[finding.severity] += 1
        for left_out in self.omitted:
            counts[left_out.severity] += left_out.count
        object.__setattr__(self, "_counts", counts)

    @property
    def errors(self) -> int:
        return self._counts[Severity.ERROR]

    @property
    def warnings(self) -> int:
        return self._counts[Severity.WARNING]

    @property
    def infos(self) -> int:
        return self._counts[Severity.INFO]

    def exit_code(self, strict: bool = False) -> int:
        """0 no errors; 1 errors (or warnings when `strict`); 2 an input could not be
        read (whatever the others gave)."""
        if self.input_errors:
            return 2
        if self.errors or (strict and self.warnings):
            return 1
        return 0

    def at_least(self, severity: Severity) -> Report:
        """The report without findings less severe than `severity` (counted in
        `hidden`)."""
        rank = _RANK[severity]
        kept = tuple(f for f in self.findings if _RANK[f.severity] >= rank)
        omitted = tuple(o for o in self.omitted if _RANK[o.severity] >= rank)
        below = sum(o.count for o in self.omitted) - sum(o.count for o in omitted)
        return Report(
            kept,
            self.catalogs,
            self.missions,
            self.hidden + len(self.findings) - len(kept) + below,
            self.input_errors,
            suppressed=self.suppressed,
            omitted=omitted,
        )

    def omitted_by_rule(self) -> dict[str, int]:
        """Rule -> how many of its findings are counted but not listed."""
        out: dict[str, int] = {}
        for left_out in self.omitted:
            out[left_out.rule] = out.get(left_out.rule, 0) + left_out.count
        return out

    def by_rule(self, rule: str) -> tuple[Finding, ...]:
        return tuple(f for f in self.findings if f.rule == rule)

    def summary(self) -> dict[str, int]:
        return {"errors": self.errors, "warnings": self.warnings, "infos": self.infos}

    def to_dict(self) -> dict[str, Any]:
        document = {
            "findings": [f.to_dict() for f in self.findings],
            "summary": self.summary(),
            "inputErrors": [e.to_dict() for e in self.input_errors],
        }
        if self.omitted:  # only with a limit (the CLI sets none for json and sarif)
            document["omitted"] = [o.to_dict() for o in self.omitted]
        return document
