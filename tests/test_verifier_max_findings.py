"""`verify --max-findings N`: a catalog with thousands of findings of one rule lists the
first N of that rule (by place) and "… and M more" in text (and github) output; json
and sarif keep every finding; the summary and the exit code count them all.

The size of a hostile catalog (1.5 million undefined list names once printed 1.5
million lines and held them all in memory) is measured in benchmarks/verify_hostile.py,
not here: these tests pin the behavior, not the speed.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.verifier import verify
from aeroexec.verifier.findings import FindingCollector

runner = CliRunner()
#: Undefined list names (AX201, an error each), plus two undefined capabilities (AX203).
UNDEFINED = 1_000


@pytest.fixture(scope="module")
def flooded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    names = ", ".join(f"l{i:04d}" for i in range(UNDEFINED))
    path = tmp_path_factory.mktemp("flood") / "catalog.yaml"
    path.write_text(
        "behavior_descriptors:\n"
        "  - behavior: B\n"
        "    recurrent: yes\n"
        f"    incompatible_lists: [{names}]\n"
        "    capabilities: [NOPE, NADA]\n"
    )
    return path


def cli(*args: str) -> tuple[int, str, str]:
    result = runner.invoke(app, ["verify", *args])
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(
        result.exception
    )
    return result.exit_code, result.stdout, result.stderr


def test_text_lists_the_first_n_of_a_rule_then_how_many_more(flooded: Path) -> None:
    code, out, err = cli(str(flooded), "--max-findings", "5")
    assert code == 1 and err == ""
    lines = out.splitlines()
    ax201 = [x for x in lines if " error AX201 " in x]
    # The first five by place: the first five names of the list.
    assert [re.search(r"'(l\d+)'", x).group(1) for x in ax201] == [  # type: ignore[union-attr]
        "l0000",
        "l0001",
        "l0002",
        "l0003",
        "l0004",
    ]
    more = lines.index(ax201[-1]) + 1
    assert lines[more] == (
        f"  … and {UNDEFINED - 5:,} more AX201 findings "
        "(--max-findings; -f json or sarif lists them all)"
    )
    # A rule under the limit is listed whole, with no "more" line.
    assert len([x for x in lines if " error AX203 " in x]) == 2
    assert not any("more AX203" in x for x in lines)
    # Every finding counts in the summary.
    errors = verify([str(flooded)]).errors
    assert errors > UNDEFINED
    assert lines[-1].startswith(f"{errors} errors, ")


def test_the_default_limit_is_100(flooded: Path) -> None:
    _, out, _ = cli(str(flooded))
    assert len([x for x in out.splitlines() if " error AX201 " in x]) == 100
    assert f"  … and {UNDEFINED - 100:,} more AX201 findings" in out


def test_zero_lists_every_finding(flooded: Path) -> None:
    _, out, _ = cli(str(flooded), "--max-findings", "0")
    assert len([x for x in out.splitlines() if " error AX201 " in x]) == UNDEFINED
    assert "… and" not in out


@pytest.mark.parametrize("fmt", ["json", "sarif"])
def test_machine_formats_keep_every_finding(flooded: Path, fmt: str) -> None:
    code, out, _ = cli(str(flooded), "-f", fmt, "--max-findings", "5")
    assert code == 1
    document = json.loads(out)
    if fmt == "json":
        rules = [f["rule"] for f in document["findings"]]
        assert document["summary"]["errors"] == verify([str(flooded)]).errors
        assert "omitted" not in document
    else:
        rules = [r["ruleId"] for r in document["runs"][0]["results"]]
    assert rules.count("AX201") == UNDEFINED


def test_github_annotations_stop_at_the_limit_with_a_notice(flooded: Path) -> None:
    code, out, _ = cli(str(flooded), "-f", "github", "--max-findings", "3")
    assert code == 1
    lines = out.splitlines()
    assert len([x for x in lines if x.startswith("::error ") and "AX201" in x]) == 3
    assert [x for x in lines if x.startswith("::notice title=AX201::")] == [
        f"::notice title=AX201::… and {UNDEFINED - 3:,} more AX201 findings "
        "(--max-findings; -f json or sarif lists them all)"
    ]


def test_the_exit_code_counts_findings_beyond_the_limit(tmp_path: Path) -> None:
    """Warnings past the limit still make --strict fail."""
    path = tmp_path / "catalog.yaml"
    path.write_text(
        "capability_descriptors:\n  - capability: C\n    processes: [p]\n"
        "    active_by_default: no\n"
        "behavior_lists:\n"
        + "".join(f"  - list: {x}\n    behaviors: [B]\n" for x in "XYZ")
        + "behavior_descriptors:\n  - behavior: B\n    recurrent: yes\n"
        "    capabilities: [C]\n    incompatible_lists: [X, X, Y, Y, Z, Z]\n"
    )
    code, out, _ = cli(str(path), "--max-findings", "1")
    assert code == 0  # three AX206 warnings, two of them past the limit
    assert out.count(" warning AX206 ") == 1
    assert "… and 2 more AX206 findings" in out
    assert out.splitlines()[-1].startswith("0 errors, 3 warnings")
    code, _, _ = cli(str(path), "--max-findings", "1", "--strict")
    assert code == 1


def test_a_negative_limit_is_a_usage_error(flooded: Path) -> None:
    code, _, err = cli(str(flooded), "--max-findings", "-1")
    assert code == 2
    assert err.splitlines() == [
        "aeroexec verify: error: invalid value for --max-findings: must be 0 (no limit) or "
        "more (aeroexec verify -h for help)"
    ]


def test_the_library_keeps_the_first_by_place_whatever_the_order_rules_yield(
    flooded: Path,
) -> None:
    every = verify([str(flooded)])
    limited = verify([str(flooded)], max_findings=7)
    for rule in {f.rule for f in every.findings}:
        assert limited.by_rule(rule) == every.by_rule(rule)[:7]
    assert limited.summary() == every.summary()
    assert limited.omitted_by_rule() == {"AX201": UNDEFINED - 7}
    # The collector keeps the first by place even when they come last and out of order.
    collector = FindingCollector(3)
    collector.extend(reversed(every.by_rule("AX201")))
    assert collector.findings() == every.by_rule("AX201")[:3]
