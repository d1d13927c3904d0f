"""The registry of verifier rules: code, name, severity, doc and the check that runs it.

Three kinds of entries:

* `loader` — diagnostics the catalog loader already emits (AX1xx, from
  `aeroexec.catalog.codes`); the verifier passes them through and documents them here;
* `catalog` — rules over a loaded catalog and its graphs (AX2xx-AX6xx);
* `mission` — checks of mission scripts against a catalog (AX70x-AX71x);
* `property` — property files' signals against a catalog (AX75x, `verify --spec`);
* `task` — rules over an Aerostack 4.x task catalog (AX81x-AX82x; its loader's
  diagnostics are AX80x, from `aeroexec.catalog.task_codes`).
* `code` — the catalog against the behavior implementations that would run it (AX9xx,
  only when the project declares its behaviors; `aeroexec.verifier.rules.code`).
* `suppression` — suppression comments that silence nothing (AX001,
  `aeroexec.verifier.suppress`).

Codes by range: AX0xx suppression comments, AX1xx loading, AX2xx references, AX3xx
capability consistency, AX4xx incompatibility, AX5xx start order, AX6xx behavior
properties (recurrent/timeout, argument specs), AX7xx missions (AX75x their property
files), AX8xx task catalogs (2020-2021), AX9xx catalog against code.
"""

from __future__ import annotations

import difflib
import importlib
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING

from aeroexec.catalog import codes, task_codes
from aeroexec.catalog.model import Severity
from aeroexec.verifier.findings import Finding

if TYPE_CHECKING:
    from aeroexec.plugins.discovery import BehaviorSet
    from aeroexec.verifier.graphs import CatalogGraphs
    from aeroexec.verifier.task_rules import TaskContext

CatalogCheck = Callable[["CatalogGraphs"], Iterable[Finding]]
CodeCheck = Callable[["CatalogGraphs", "BehaviorSet"], Iterable[Finding]]
TaskCheck = Callable[["TaskContext"], Iterable[Finding]]

KINDS = ("loader", "catalog", "mission", "property", "task", "code", "suppression")

AREAS = {
    "AX0": "Suppression comments",
    "AX1": "Loading (reported by the catalog loader)",
    "AX2": "References",
    "AX3": "Capability consistency",
    "AX4": "Incompatibility",
    "AX5": "Start order",
    "AX6": "Behavior properties",
    "AX7": "Missions and their properties",
    "AX8": "Task catalogs (Aerostack 4.x, 2020-2021)",
    "AX9": "Catalog against code",
}


@dataclass(frozen=True, slots=True)
class Rule:
    code: str
    name: str
    #: The severity of its findings; None for loader codes whose severity varies.
    severity: Severity | None
    #: One paragraph: what it is, how it fails in flight, how to fix it.
    doc: str
    kind: str
    check: CatalogCheck | TaskCheck | CodeCheck | None = None
    #: Findings of this rule carry a witness (an activation sequence) when one exists.
    witness: bool = False

    @property
    def area(self) -> str:
        return AREAS.get(self.code[:3], "Other")

    def explain(self) -> str:
        severity = self.severity.value if self.severity else "as reported"
        lines = [f"{self.code} {self.name} ({severity}; {self.area.lower()})", "", self.doc]
        if self.witness:
            lines += [
                "",
                "Findings of this rule carry a witness: the shortest activation sequence "
                "that makes the problem happen in the executive (`--witness`).",
            ]
        return "\n".join(lines)


_RULES: dict[str, Rule] = {}


def register(rule: Rule) -> Rule:
    if rule.kind not in KINDS:
        raise ValueError(f"unknown rule kind {rule.kind!r}")
    if rule.code in _RULES and _RULES[rule.code] != rule:
        raise ValueError(f"rule code {rule.code} registered twice")
    _RULES[rule.code] = rule
    return rule


def catalog_rule(
    code: str, name: str, severity: Severity, doc: str, *, witness: bool = False
) -> Callable[[CatalogCheck], CatalogCheck]:
    """Decorator: register a check over `CatalogGraphs` as rule `code`."""

    def decorate(check: CatalogCheck) -> CatalogCheck:
        register(Rule(code, name, severity, " ".join(doc.split()), "catalog", check, witness))
        return check

    return decorate


def code_rule(
    code: str, name: str, severity: Severity, doc: str
) -> Callable[[CodeCheck], CodeCheck]:
    """Decorator: register a check of a catalog against behavior implementations."""

    def decorate(check: CodeCheck) -> CodeCheck:
        register(Rule(code, name, severity, " ".join(doc.split()), "code", check))
        return check

    return decorate


def task_rule(
    code: str, name: str, severity: Severity, doc: str, *, witness: bool = False
) -> Callable[[TaskCheck], TaskCheck]:
    """Decorator: register a check over a task catalog (`TaskContext`) as rule `code`."""

    def decorate(check: TaskCheck) -> TaskCheck:
        register(Rule(code, name, severity, " ".join(doc.split()), "task", check, witness))
        return check

    return decorate


def mission_rule(code: str, name: str, severity: Severity, doc: str) -> Rule:
    return register(Rule(code, name, severity, " ".join(doc.split()), "mission"))


def property_rule(code: str, name: str, severity: Severity, doc: str) -> Rule:
    """A check of a property file's signals against a catalog (`verify --spec`)."""
    return register(Rule(code, name, severity, " ".join(doc.split()), "property"))


#: Severity of each loader diagnostic as `aeroexec.catalog.loader` emits it.
_LOADER_SEVERITY = {
    codes.MISSING_ERROR_TAG: Severity.ERROR,
    codes.MISSING_WARNING_TAG: Severity.WARNING,
    codes.MISSING_DEPENDENCY_TAG: Severity.INFO,
    codes.UNKNOWN_TAG: Severity.WARNING,
    codes.WRONG_TYPE: Severity.ERROR,
    codes.DUPLICATE_DEFINITION: Severity.WARNING,
    codes.DUPLICATE_KEY: Severity.WARNING,
    codes.MALFORMED_ARGUMENT: Severity.ERROR,
    codes.DIALECT: Severity.INFO,
    codes.IGNORED_SECTION: Severity.INFO,
    codes.SCALAR_FOR_LIST: Severity.WARNING,
}

for _code, (_name, _doc) in codes.LOADER_DOCS.items():
    register(Rule(_code, _name, _LOADER_SEVERITY.get(_code), _doc, "loader"))
for _code, (_name, _severity, _doc) in task_codes.TASK_LOADER_DOCS.items():
    register(Rule(_code, _name, _severity, _doc, "loader"))


#: The modules whose import registers the rules of each kind (loader rules are above).
#: Only the kind asked for is imported: verifying a catalog does not load the mission
#: checks and the executive they run (start-up time).
_RULE_MODULES: dict[str, tuple[str, ...]] = {
    "loader": (),
    "catalog": ("aeroexec.verifier.rules",),
    "code": ("aeroexec.verifier.rules",),
    "mission": (
        "aeroexec.verifier.missions",
        "aeroexec.verifier.mission_run",
        "aeroexec.verifier.bt_missions",
    ),
    "property": ("aeroexec.verifier.signals",),
    "task": ("aeroexec.verifier.task_rules",),
    "suppression": ("aeroexec.verifier.suppress",),
}


def _load_rule_modules(kind: str | None = None) -> None:
    # Rules register themselves on import; importing here keeps `all_rules()` complete
    # whichever module a caller imported first.
    kinds = _RULE_MODULES.values() if kind is None else [_RULE_MODULES.get(kind, ())]
    for modules in kinds:
        for module in modules:
            importlib.import_module(module)


def all_rules(kind: str | None = None) -> tuple[Rule, ...]:
    """Every registered rule (of one kind), sorted by code."""
    _load_rule_modules(kind)
    return tuple(rule for code, rule in sorted(_RULES.items()) if kind is None or rule.kind == kind)


def get(code: str) -> Rule | None:
    _load_rule_modules()
    return _RULES.get(code.strip().upper())


def suggest_code(code: str) -> str:
    _load_rule_modules()
    wanted = code.strip().upper()
    by_name = {rule.name: rule.code for rule in _RULES.values()}
    if code.strip().lower() in by_name:
        return f" (did you mean {by_name[code.strip().lower()]}?)"
    close = difflib.get_close_matches(wanted, list(_RULES), n=1, cutoff=0.6)
    return f" (did you mean {close[0]}?)" if close else ""


def catalog_checks() -> Iterator[Rule]:
    for rule in all_rules("catalog"):
        if rule.check is not None:
            yield rule


def code_checks() -> Iterator[Rule]:
    for rule in all_rules("code"):
        if rule.check is not None:
            yield rule


def task_checks() -> Iterator[Rule]:
    for rule in all_rules("task"):
        if rule.check is not None:
            yield rule
