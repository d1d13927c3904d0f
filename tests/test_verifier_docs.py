"""docs/rules.md is generated from the registry and up to date; every rule is documented."""

from __future__ import annotations

from pathlib import Path

from aeroexec.verifier import all_rules
from aeroexec.verifier.docs import render_rules_markdown

ROOT = Path(__file__).resolve().parent.parent


def test_rules_md_is_up_to_date() -> None:
    current = (ROOT / "docs" / "rules.md").read_text(encoding="utf-8")
    assert current == render_rules_markdown(), (
        "docs/rules.md is stale: python -m aeroexec.verifier.docs > docs/rules.md"
    )


def test_every_rule_has_a_paragraph_with_flight_effect_and_fix() -> None:
    for rule in all_rules():
        assert rule.doc.count("\n") == 0, rule.code
        if rule.kind == "loader" and rule.code in {"AX103", "AX109", "AX110", "AX807"}:
            continue  # informational loader notes
        assert "Fix" in rule.doc, rule.code
        if rule.kind != "loader":
            assert "In flight" in rule.doc, rule.code


def test_codes_follow_the_ranges() -> None:
    kinds = {"AX0": "suppression", "AX1": "loader", "AX7": "mission", "AX9": "code"}
    for rule in all_rules():
        assert len(rule.code) == 5 and rule.code.startswith("AX")
        kind = kinds.get(rule.code[:3], "catalog")
        if rule.code.startswith("AX8"):  # task catalogs: AX801-AX810 loader, then rules
            kind = "loader" if int(rule.code[2:]) <= 810 else "task"
        if rule.code.startswith("AX75"):  # the signals of property files (verify --spec)
            kind = "property"
        assert rule.kind == kind, rule.code


def test_pre_commit_hooks_run_verify_on_catalogs() -> None:
    import re

    import yaml

    hooks = yaml.safe_load((ROOT / ".pre-commit-hooks.yaml").read_text(encoding="utf-8"))
    by_id = {hook["id"]: hook for hook in hooks}
    assert by_id["aeroexec-verify"]["entry"] == "aeroexec verify"
    assert by_id["aeroexec-verify-strict"]["entry"] == "aeroexec verify --strict"
    for hook in hooks:
        assert hook["language"] == "python"
        assert {"id", "name", "entry", "language"} <= set(hook)
        pattern = re.compile(hook["files"])
        for path in (
            "catalog/default.yaml",
            "config/drone1/behavior_catalog.yaml",
            "drone1/catalog_imav.yml",
            "catalogs/x.yaml",
        ):
            assert pattern.search(path), (hook["id"], path)
        for path in ("world.yaml", "catalog/sub/README.md", ".github/workflows/ci.yaml"):
            assert not pattern.search(path), (hook["id"], path)
