"""The catalog against the code on the real Aerostack catalogs: the argument name the
standard GO_TO_POINT reads versus what the flown catalogs call it."""

from __future__ import annotations

from pathlib import Path

from aeroexec.catalog import read_catalog
from aeroexec.plugins import BehaviorSet, BehaviorSources, discover
from aeroexec.verifier import check_catalog, verify

REAL = Path(__file__).resolve().parent / "fixtures" / "verifier_catalogs"
QC = "Ahrovan+quadrotor_stack_configs__drone1_behavior_catalog__{}.yaml"


def standard_library_only() -> BehaviorSet:
    return discover(BehaviorSources(config=(), config_file=None, entry_points=False))


def test_position_is_not_what_go_to_point_reads() -> None:
    catalog = read_catalog(REAL / QC.format("451fc45"))
    findings = check_catalog(catalog, behaviors=standard_library_only())
    ax903 = [f for f in findings if f.rule == "AX903"]
    assert [(f.line, f.column, f.message) for f in ax903] == [
        (
            17,
            9,
            "GO_TO_POINT: argument POSITION is not read by aeroexec.behaviors.motion:GoToPoint, "
            "which reads COORDINATES, RELATIVE_COORDINATES",
        )
    ]
    assert {f.subjects[0] for f in findings if f.rule == "AX901"} == {
        "KEEP_MOVING",
        "SELF_LOCALIZE_BY_ODOMETRY",
        "SELF_LOCALIZE_BY_VISUAL_MARKER",
    }


def test_lower_case_spelling_is_what_go_to_point_reads() -> None:
    catalog = read_catalog(REAL / QC.format("85c888c"))
    findings = check_catalog(catalog, behaviors=standard_library_only())
    assert not [f for f in findings if f.rule == "AX903" and "GO_TO_POINT" in f.subjects]


def test_without_a_declared_behavior_set_no_code_rule_runs() -> None:
    report = verify([REAL / QC.format("451fc45")])
    assert not [f for f in report.findings if f.rule.startswith("AX9")]
