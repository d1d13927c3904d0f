"""The verifier over every real Aerostack catalog (copies in fixtures/verifier_catalogs).

Each catalog's findings are kept as a reviewed JSON snapshot in
`fixtures/verifier_catalogs/expected/` (loader infos AX103/AX109 left out: they are the
loader's business and say nothing about defects). After a deliberate change, regenerate
with `AEROEXEC_UPDATE_SNAPSHOTS=1 pytest tests/test_verifier_real.py` and review the
diff. The defects NOTES.md section 2 lists for these catalogs are asserted one by one,
and docs/verifier-findings.md explains them.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import pytest

from aeroexec.catalog import THESIS_CATALOG
from aeroexec.errors import CatalogError
from aeroexec.verifier import Finding, Outcome, Report, verify, verify_catalog_file

ROOT = Path(__file__).resolve().parent.parent
REAL = Path(__file__).resolve().parent / "fixtures" / "verifier_catalogs"
EXPECTED = REAL / "expected"
CATALOGS = sorted(REAL.glob("*.yaml"))
UPDATE = os.environ.get("AEROEXEC_UPDATE_SNAPSHOTS") == "1"
LEFT_OUT = {"AX103", "AX109", "AX807"}

DRONE1 = "Ahrovan+quadrotor_stack_configs__drone1_"
C0349293 = REAL / f"{DRONE1}behavior_catalog__0349293.yaml"
C451FC45 = REAL / f"{DRONE1}behavior_catalog__451fc45.yaml"
CE3EAC89 = REAL / f"{DRONE1}behavior_catalog__e3eac89.yaml"
C85C888C = REAL / f"{DRONE1}behavior_catalog__85c888c.yaml"
CCD745C9 = REAL / f"{DRONE1}behavior_catalog__cd745c9.yaml"
IMAV_EAD04DD = REAL / f"{DRONE1}catalog_imav__ead04dd.yaml"
IMAV_0281478 = REAL / f"{DRONE1}catalog_imav__0281478.yaml"
DRONE2 = REAL / "Ahrovan+quadrotor_stack_configs__drone2_catalog_imav_mission2__0b01192.yaml"
DRONE4 = REAL / "Ahrovan+quadrotor_stack_configs__drone4_catalog_imav__cad9aae.yaml"
DRONE5 = REAL / "Ahrovan+quadrotor_stack_configs__drone5_catalog_imav__0281478.yaml"
JACEK = REAL / "JacekCieslak95+behavior_take_off2__behavior_catalog__8bbe12d.yaml"


def snapshot(path: Path) -> dict[str, Any]:
    try:
        report = verify_catalog_file(path)
    except CatalogError as exc:
        return {"catalog": path.name, "readable": False, "error": exc.message}
    findings = []
    for finding in report.findings:
        if finding.rule in LEFT_OUT:
            continue
        entry = finding.to_dict()
        del entry["file"]
        # Call paths (helper calls) belong to mission findings only.
        assert entry.pop("related") == []
        findings.append(entry)
    return {"catalog": path.name, "readable": True, "findings": findings}


def report_of(path: Path) -> Report:
    return verify_catalog_file(path)


def at(report: Report, rule: str, line: int) -> list[Finding]:
    return [f for f in report.findings if f.rule == rule and f.line == line]


def test_every_real_catalog_is_copied() -> None:
    assert len(CATALOGS) == 19
    assert len(list(EXPECTED.glob("*.json"))) == len(CATALOGS)


@pytest.mark.parametrize("path", CATALOGS, ids=lambda p: p.name[:60])
def test_findings_match_the_reviewed_snapshot(path: Path) -> None:
    expected_file = EXPECTED / f"{path.stem}.json"
    current = snapshot(path)
    if UPDATE:
        expected_file.write_text(json.dumps(current, indent=2) + "\n", encoding="utf-8")
    assert expected_file.exists(), f"no reviewed snapshot for {path.name}"
    assert current == json.loads(expected_file.read_text(encoding="utf-8"))


# -- the defects of NOTES.md section 2, one by one ------------------------------------------
TYPO_CATALOGS = [
    (IMAV_EAD04DD, 29),
    (IMAV_0281478, 29),
    (C0349293, 85),
    (C451FC45, 70),
    (CE3EAC89, 71),
    (C85C888C, 71),
    (CCD745C9, 71),
    (JACEK, 106),
]


@pytest.mark.parametrize(("path", "line"), TYPO_CATALOGS, ids=lambda v: getattr(v, "name", v))
def test_self_localizaion_typo_is_an_undefined_list(path: Path, line: int) -> None:
    [finding] = at(report_of(path), "AX201", line)
    assert finding.column == 26
    assert finding.subjects == ("SELF_LOCALIZE_BY_VISUAL_MARKER", "self_localizaion_behaviors")
    assert "did you mean 'self_localization_behaviors'?" in finding.message


def test_flown_imav_catalog_lists_undefined_behaviors() -> None:
    report = report_of(IMAV_EAD04DD)
    members = {f.subjects[1]: f.line for f in report.by_rule("AX202")}
    assert members == {
        "FLIP": 43,
        "KEEP_HOVERING": 44,
        "FOLLOW_OBJECT_IMAGE": 45,
        "LAND_ON_STATIC_PLATFORM": 46,
        "KEEP_MOVING": 47,
        "SELF_LOCALIZE_BY_VISUAL_MARKERS": 54,
        "SELF_LOCALIZE_BY_LIDAR": 55,
    }
    plural = next(f for f in report.by_rule("AX202") if f.line == 54)
    assert "did you mean 'SELF_LOCALIZE_BY_VISUAL_MARKER'?" in plural.message


def test_visual_servo_manuel_is_an_undefined_capability_of_the_replaced_definition() -> None:
    [finding] = at(report_of(C0349293), "AX203", 74)
    assert finding.subjects == ("LAND_ON_STATIC_PLATFORM", "VISUAL_SERVO_MANUEL")
    assert "did you mean 'VISUAL_SERVOING_MANUEL'?" in finding.message
    assert "which the one at line 93 replaces" in finding.message
    assert finding.witness is None  # the executive never sees that definition


def test_duplicate_land_on_static_platform() -> None:
    [finding] = report_of(C0349293).by_rule("AX106")
    assert (finding.line, finding.column) == (93, 5)
    assert "first at line 72" in finding.message


@pytest.mark.parametrize("path", [IMAV_0281478, DRONE2, DRONE4], ids=lambda p: p.name[-20:])
def test_visual_servoing_is_an_undefined_incompatible_capability(path: Path) -> None:
    [finding] = report_of(path).by_rule("AX204")
    assert finding.subjects == ("SETPOINT_BASED_FLIGHT_CONTROL", "VISUAL_SERVOING")
    assert finding.column == 33


@pytest.mark.parametrize(
    ("path", "line"), [(CE3EAC89, 130), (C85C888C, 130), (CCD745C9, 135)], ids=str
)
def test_removed_capability_still_required(path: Path, line: int) -> None:
    [finding] = at(report_of(path), "AX205", line)
    assert finding.subjects[:2] == (
        "OBSTACLE_DETECTION_BY_VISUAL_MARKERS",
        "SELF_LOCALIZATION_BY_VISUAL_MARKERS",
    )
    assert finding.witness is not None
    assert [s.activate for s in finding.witness.steps] == ["SELF_LOCALIZE_BY_VISUAL_MARKER"]
    assert finding.witness.outcome is Outcome.REJECTED


def test_drone5_has_no_capability_descriptors() -> None:
    report = report_of(DRONE5)
    [finding] = report.by_rule("AX101")
    assert (finding.line, finding.column) == (1, 1)
    assert "capability_descriptors" in finding.message
    assert report.exit_code() == 1


def test_land_on_static_platform_without_lists_is_one_sided() -> None:
    [finding] = report_of(C0349293).by_rule("AX401")
    assert finding.subjects[0] == "LAND_ON_STATIC_PLATFORM"
    assert (finding.line, finding.column) == (93, 5)
    assert finding.witness is not None


def test_every_real_catalog_is_read_seven_as_task_catalogs() -> None:
    from aeroexec.catalog.formats import read_any_catalog
    from aeroexec.catalog.tasks import TaskCatalog

    assert all(snapshot(p)["readable"] for p in CATALOGS)
    tasks = [p for p in CATALOGS if isinstance(read_any_catalog(p), TaskCatalog)]
    assert len(tasks) == 7
    assert all("4edaaf8" in p.name or "catalog__" in p.name for p in tasks)


# -- the thesis: Appendix A catalog and Appendix C mission ----------------------------------
def test_appendix_a_defects() -> None:
    report = verify([THESIS_CATALOG])
    errors = {(f.rule, f.line, f.column): f for f in report.findings if f.severity.value == "error"}
    assert set(errors) == {("AX202", 113, 9), ("AX202", 116, 25)}
    assert errors[("AX202", 113, 9)].message == (
        "list motion_behaviors: VISUAL_SERVOING is a capability, not a behavior"
    )
    assert errors[("AX202", 116, 25)].subjects == ("rotation_behaviors", "LOOK_AT_POINT")
    warnings = {(f.rule, f.subjects[0]) for f in report.findings if f.severity.value == "warning"}
    assert warnings == {
        ("AX102", "SELF_LOCALIZATION_BY_VISUAL_MARKERS"),
        ("AX102", "VISUAL_MARKERS_RECOGNITION"),
        ("AX602", "KEEP_HOVERING"),
        ("AX602", "WAIT"),
    }


def test_appendix_c_mission_against_appendix_a() -> None:
    mission = ROOT / "missions" / "appendix_c.py"
    lines = mission.read_text(encoding="utf-8").splitlines()
    report = verify([THESIS_CATALOG], missions=[mission])
    mission_findings = [f for f in report.findings if f.file == str(mission)]
    where = {
        "activateBehavior": next(
            i for i, t in enumerate(lines, 1) if "api.activateBehavior('PAY_ATTENTION_TO" in t
        ),
        "inhibitBehavior": next(
            i for i, t in enumerate(lines, 1) if "api.inhibitBehavior('PAY_ATTENTION_TO" in t
        ),
    }
    assert [(f.rule, f.line) for f in mission_findings] == [
        ("AX701", where["activateBehavior"]),
        ("AX701", where["inhibitBehavior"]),
    ]
    for finding, function in zip(mission_findings, where, strict=True):
        text = lines[finding.line - 1]
        assert finding.column == text.index("'PAY_ATTENTION_TO") + 1
        assert finding.message == (
            f"{function}('PAY_ATTENTION_TO_VISUAL_MARKERS'): unknown behavior "
            "PAY_ATTENTION_TO_VISUAL_MARKERS (did you mean 'PAY_ATTENTION'?)"
        )
        assert finding.subjects == ("PAY_ATTENTION_TO_VISUAL_MARKERS",)


def test_appendix_c_mission_against_the_default_catalog_leaves_attention_running() -> None:
    """Every call of the thesis' mission is valid against the default catalog; as a
    sequence, its `else` branch (position unknown: land and return) never inhibits
    the recurrent PAY_ATTENTION_TO_VISUAL_MARKERS activated before it."""
    from aeroexec.catalog import DEFAULT_CATALOG

    mission = ROOT / "missions" / "appendix_c.py"
    lines = mission.read_text(encoding="utf-8").splitlines()
    report = verify([DEFAULT_CATALOG], missions=[mission])
    [finding] = [f for f in report.findings if f.severity.value != "info"]
    activation = next(i for i, t in enumerate(lines, 1) if "api.activateBehavior(" in t)
    landing = next(i for i, t in enumerate(lines, 1) if "Position unknown, landing" in t)
    assert (finding.rule, finding.line, finding.column) == ("AX712", activation, 5)
    assert [(s.action, s.detail) for s in finding.path] == [
        ("execute", "TAKE_OFF"),
        ("activate", "PAY_ATTENTION_TO_VISUAL_MARKERS"),
        ("execute", "GO_TO_POINT"),
        ("else", ""),
        ("execute", "LAND"),
        ("return", ""),
    ]
    assert finding.path[4].line == landing + 1
    assert "still running when the mission ends" in finding.message
