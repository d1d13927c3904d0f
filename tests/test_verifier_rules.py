"""Every rule of the registry has a fixture that triggers it, at the places the fixture
marks with `# expect CODE [at TOKEN]` comments (line, and the column where TOKEN starts),
and a clean near-miss fixture where it stays silent. The catalog-against-code rules
(AX9xx) check their fixtures against the behaviors of `code_behaviors.py`."""

from __future__ import annotations

import re
from collections import defaultdict
from pathlib import Path

import pytest

from aeroexec.catalog import read_catalog
from aeroexec.catalog.formats import read_any_catalog
from aeroexec.catalog.model import Severity
from aeroexec.catalog.paths import DEFAULT_CATALOG
from aeroexec.catalog.tasks import TaskCatalog
from aeroexec.plugins import BehaviorSet, BehaviorSources, discover
from aeroexec.properties.spec import load_properties
from aeroexec.verifier import Finding, Rule, all_rules, check_mission, verify
from aeroexec.verifier.bt_missions import check_bt_mission, read_bt_mission
from aeroexec.verifier.engine import check_any_catalog
from aeroexec.verifier.missions import read_mission
from aeroexec.verifier.signals import SignalUse, check_signal_uses

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "verifier"
RULES = FIXTURES / "rules"
TASKS = FIXTURES / "tasks"
MISSIONS = FIXTURES / "missions"
PROPERTIES = FIXTURES / "properties"
#: Behavior-tree missions (YAML) and their task catalogs (AX716-AX717).
TREES = FIXTURES / "bt"
MISSION_CATALOG = MISSIONS / "catalog.yaml"
CODE_BEHAVIORS = FIXTURES / "code_behaviors.py"
#: Rules that fire on every catalog (the dialect notes): they have no clean fixture.
ALWAYS = {"AX109", "AX807"}

EXPECT = re.compile(r"expect\s+(AX\d{3})(?:\s+at\s+(\S+))?")

Place = tuple[int, int | None]


def expectations(path: Path) -> dict[str, set[Place]]:
    """code -> {(line, column or None)} from the fixture's `# expect` comments."""
    expected: dict[str, set[Place]] = defaultdict(set)
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        code_part, _, comment = line.partition("# expect")
        if not comment:
            continue
        for match in EXPECT.finditer("expect" + comment):
            code, token = match.groups()
            column = code_part.index(token) + 1 if token else None
            expected[code].add((number, column))
    return expected


def fixture_for(rule: Rule, clean: bool = False) -> Path:
    if rule.kind == "property":
        return PROPERTIES / f"{rule.code}{'.clean' if clean else ''}.yaml"
    if rule.kind == "mission":
        tree = TREES / f"{rule.code}{'.clean' if clean else ''}.yaml"
        return tree if tree.exists() else MISSIONS / f"{rule.code}{'.clean' if clean else ''}.py"
    folder = TASKS if rule.code.startswith("AX8") else RULES
    path = folder / f"{rule.code}{'.clean' if clean else ''}.yaml"
    if clean and not path.exists():
        return folder / "clean.yaml"
    return path


def code_behaviors() -> BehaviorSet:
    return discover(BehaviorSources(command_line=(str(CODE_BEHAVIORS),), entry_points=False))


def mission_catalog(path: Path) -> Path:
    """`# catalog: NAME` on a mission fixture's first line names its catalog."""
    first = path.read_text(encoding="utf-8").splitlines()[0]
    if first.startswith("# catalog:"):
        return MISSIONS / first.removeprefix("# catalog:").split()[0]
    return MISSION_CATALOG


def findings_of(path: Path, rule: Rule | None = None) -> list[Finding]:
    if path.parent == PROPERTIES:  # a property file, against the default catalog
        props = load_properties([str(path)]).properties
        uses = [SignalUse(name, mark) for p in props for name, mark in p.formula.uses]
        return check_signal_uses(uses, read_catalog(DEFAULT_CATALOG))
    if path.suffix == ".py":
        return check_mission(read_mission(path), read_catalog(mission_catalog(path)))
    if path.parent == TREES:
        first = path.read_text(encoding="utf-8").splitlines()[0]
        catalog = read_any_catalog(TREES / first.removeprefix("# catalog:").strip())
        assert isinstance(catalog, TaskCatalog)
        return check_bt_mission(read_bt_mission(str(path)), catalog)
    if rule is not None and rule.kind == "suppression":  # decided over a whole run
        return list(verify([str(path)]).findings)
    behaviors = code_behaviors() if rule is not None and rule.kind == "code" else None
    return check_any_catalog(read_any_catalog(path), behaviors=behaviors)


def _ids(rule: Rule) -> str:
    return rule.code


@pytest.mark.parametrize("rule", all_rules(), ids=_ids)
def test_rule_fires_exactly_where_the_fixture_says(rule: Rule) -> None:
    path = fixture_for(rule)
    assert path.exists(), f"every rule needs a fixture: {path.name} is missing"
    expected = expectations(path)[rule.code]
    assert expected, f"{path.name} marks no '# expect {rule.code}' place"
    found = [f for f in findings_of(path, rule) if f.rule == rule.code]
    assert found, f"{rule.code} did not fire on {path.name}"
    places = {(f.line, f.column) for f in found}
    lines_only = {line for line, column in expected if column is None}
    wanted = {p for p in expected if p[1] is not None}
    got_with_columns = {p for p in places if p[0] not in lines_only}
    assert got_with_columns == wanted, "\n".join(str(f) for f in found)
    assert {line for line, _ in places if line in lines_only} == lines_only
    for finding in found:
        assert finding.file == str(path)
        if rule.severity is not None:
            assert finding.severity is rule.severity
        if rule.kind != "loader":
            assert finding.subjects, f"{finding} names no subject"


@pytest.mark.parametrize("rule", [r for r in all_rules() if r.code not in ALWAYS], ids=_ids)
def test_rule_is_silent_on_its_clean_fixture(rule: Rule) -> None:
    path = fixture_for(rule, clean=True)
    assert path.exists(), f"every rule needs a clean fixture: {path.name} is missing"
    findings = findings_of(path, rule)
    assert [str(f) for f in findings if f.rule == rule.code] == []
    assert [str(f) for f in findings if f.severity is Severity.ERROR] == []


def test_the_shared_clean_catalog_has_nothing_above_info() -> None:
    findings = findings_of(RULES / "clean.yaml")
    assert [str(f) for f in findings if f.severity is not Severity.INFO] == []
    assert {f.rule for f in findings} == {"AX109"}


def test_the_clean_task_catalog_has_nothing_above_info() -> None:
    findings = findings_of(TASKS / "clean.yaml")
    assert [str(f) for f in findings if f.severity is not Severity.INFO] == []
    assert {f.rule for f in findings} == {"AX807"}


def test_every_fixture_belongs_to_a_registered_rule() -> None:
    codes = {rule.code for rule in all_rules()}
    for path in [*RULES.glob("AX*"), *MISSIONS.glob("AX*"), *TASKS.glob("AX*")]:
        assert path.name[:5] in codes, f"{path.name} names no registered rule"
