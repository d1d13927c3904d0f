"""Fuzzing against the planted catalogs of the verifier's rules (issue 27): each class the
verifier knows either gets a dynamic witness from the fuzzer, which the cross-check maps
to the rule and line, or is static-only with its reason; and a counterexample fails the
same way every time it is run and checked."""

from __future__ import annotations

from pathlib import Path

import pytest

from aeroexec.catalog.loader import load_catalog
from aeroexec.errors import AeroexecError
from aeroexec.fuzz.crosscheck import STATIC_ONLY, cross_check
from aeroexec.fuzz.oracle import Bench, Target, run_files, run_mission
from aeroexec.fuzz.output import write_counterexample
from aeroexec.fuzz.search import Budget, Finding, fuzz
from aeroexec.fuzz.steps import EXECUTE, Command, commands
from aeroexec.properties.check import VIOLATED, check_recording
from aeroexec.verifier.engine import verify_catalog_file

ROOT = Path(__file__).resolve().parent.parent
PLANTED = ROOT / "tests" / "fixtures" / "verifier" / "rules"
#: The classes whose defect a generated mission makes violate a property.
WITNESSED = {"AX305": "compatible_capabilities"}
CATALOG_ERRORS = sorted(
    p for p in PLANTED.glob("AX*.yaml") if ".clean" not in p.name and p.stem < "AX7"
)


def test_a_self_incompatible_capability_is_witnessed_and_mapped_to_its_rule() -> None:
    path = PLANTED / "AX305.yaml"
    report = fuzz(Target(str(path), allow_unimplemented=True), Budget(runs=100), seed_value=0)
    found = {f.name: f for f in report.findings}
    assert set(found) == {"compatible_capabilities"}
    assert len(commands(found["compatible_capabilities"].mission)) <= 10
    static = verify_catalog_file(path).findings
    check = cross_check(load_catalog(path), report.findings, static)
    (row,) = check.dynamic
    assert [(m.rule, m.line) for m in row.matches] == [
        (f.rule, f.line) for f in static if f.rule == "AX305"
    ]
    witnessed = [s for s in check.static if s.finding.rule == "AX305"]
    assert witnessed and all(s.witness is not None for s in witnessed)


@pytest.mark.parametrize("path", CATALOG_ERRORS, ids=lambda p: p.stem)
def test_every_planted_error_is_witnessed_or_static_only_with_a_reason(path: Path) -> None:
    static = verify_catalog_file(path).findings
    target = Target(str(path), allow_unimplemented=True)
    try:
        bench = Bench.of(target)
        run_mission(bench, ())
    except AeroexecError:
        # the executive refuses the catalog: every error is static-only, for that reason
        assert path.stem in STATIC_ONLY and "nothing runs" in STATIC_ONLY[path.stem]
        return
    report = fuzz(target, Budget(runs=40), seed_value=0)
    check = cross_check(bench.catalog, report.findings, static)
    for row in check.static:
        if row.finding.rule in WITNESSED:
            continue
        assert row.witness is None and row.reason, row
        if row.finding.rule == path.stem and row.finding.severity.value == "error":
            assert row.finding.rule in STATIC_ONLY, f"{path.stem} needs its reason"
    names = {f.name for f in report.findings}
    assert names <= set(WITNESSED.values()), names


@pytest.mark.parametrize(
    "path", [PLANTED / "AX602.yaml", PLANTED / "AX604.yaml"], ids=["AX602", "AX604"]
)
def test_a_timeout_shorter_than_its_goal_breaks_no_property(path: Path) -> None:
    """The planted catalogs have no take-off (the vehicle never leaves the ground), and
    their behavior's TIME_OUT is an answer: the fuzzer finds nothing, and the rule's
    static-only reason says why."""
    report = fuzz(Target(str(path), allow_unimplemented=True), Budget(runs=100), seed_value=0)
    assert report.findings == []
    assert "TIME_OUT" in STATIC_ONLY[path.stem]


@pytest.mark.parametrize(("go_to", "land"), [(30, 15), (30, 300), (300, 15), (300, 300)])
def test_landing_in_time_depends_on_lands_timeout_not_go_to_points(
    tmp_path: Path, go_to: int, land: int
) -> None:
    """AX604's catalog given a take-off and a landing, climbing as high as it allows: the
    vehicle ends in the air exactly when LAND's timeout is short, whether GO_TO_POINT's
    covers the travel (300 s) or not (30 s, AX604), so the violation is no witness of
    AX604 and the cross-check does not call it one."""
    planted = (PLANTED / "AX604.yaml").read_text(encoding="utf-8")
    flown = planted.replace("timeout: 30", f"timeout: {go_to}").replace(
        "behavior_descriptors:\n",
        "behavior_descriptors:\n"
        "  - behavior: TAKE_OFF\n    timeout: 30\n    recurrent: no\n"
        f"  - behavior: LAND\n    timeout: {land}\n    recurrent: no\n",
    )
    catalog = tmp_path / "flown.yaml"
    catalog.write_text(flown, encoding="utf-8")
    static = verify_catalog_file(catalog).findings
    assert ("AX604" in {f.rule for f in static}) == (go_to == 30)
    bench = Bench.of(Target(str(catalog), allow_unimplemented=True))
    climb = (
        Command(EXECUTE, "TAKE_OFF"),
        Command(EXECUTE, "GO_TO_POINT", (("COORDINATES", [0, 0, 100]),)),
    )
    judgement = run_mission(bench, climb)
    names = [v.name for v in judgement.violations]
    assert names == (["ends_landed_disarmed"] if land == 15 else [])
    if names:
        finding = Finding(names[0], judgement.violations[0].message, climb)
        (row,) = cross_check(bench.catalog, [finding], static).dynamic
        assert row.matches == ()


def test_a_counterexample_fails_the_same_way_a_hundred_times(tmp_path: Path) -> None:
    """`aeroexec run` of the written files, then `aeroexec check` of its recording, as
    the commands do them: the same violation and the same recording, 100 times of 100."""
    path = PLANTED / "AX305.yaml"
    target = Target(str(path), allow_unimplemented=True)
    bench = Bench.of(target)
    (finding,) = fuzz(target, Budget(runs=100), seed_value=0).findings
    written = write_counterexample(bench, tmp_path / "ce", finding, 0)
    assert written.reproduced
    first = (tmp_path / "ce" / "run.mcap").read_bytes()
    for attempt in range(100):
        record = tmp_path / f"again{attempt % 2}.mcap"
        judgement = run_files(
            bench, tmp_path / "ce" / "mission.py", tmp_path / "ce" / "world.yaml", record
        )
        assert [v.name for v in judgement.violations] == [finding.name]
        checked = check_recording(record, bench.properties)
        assert [v.name for v in checked.verdicts if v.status == VIOLATED] == [finding.name]
        assert record.read_bytes() == first


def test_the_findings_page_covers_the_twelve_flown_catalogs() -> None:
    """docs/fuzz-findings.md (scripts/fuzz-findings) has a section for each Aerostack 2.x
    catalog of the fixtures, and every row's verdict is one the cross-check gives."""
    page = (ROOT / "docs" / "fuzz-findings.md").read_text(encoding="utf-8")
    real = ROOT / "tests" / "fixtures" / "catalogs" / "real"
    flown = sorted(real.glob("Ahrovan+*.yaml")) + sorted(real.glob("JacekCieslak95+*.yaml"))
    assert len(flown) == 12
    for path in flown:
        assert f"\n## {path.name}\n" in page, path.name
    assert "scripts/fuzz-findings > docs/fuzz-findings.md" in page
    for line in page.splitlines():
        if line.startswith("| AX"):
            verdict = line.rstrip(" |").rsplit(" | ", 1)[1]
            assert verdict.startswith(("static-only: ", "`")), line
