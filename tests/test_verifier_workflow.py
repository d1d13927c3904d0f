"""ruff's workflow on `aeroexec verify`: --select/--ignore/--extend-select by code and
prefix, --statistics, suppression in place (`# noqa: AX711` in a mission, `# aeroexec:
ignore[AX401]` in a catalog), per-file ignores, all of it in [tool.aeroexec.verify],
and a bare `aeroexec verify` that checks what the project lists."""

from __future__ import annotations

import json
import shutil
import textwrap
from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.catalog import DEFAULT_CATALOG
from aeroexec.cli import app
from aeroexec.errors import AeroexecError
from aeroexec.verifier.selection import RuleSelection, SelectionLayer

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "verifier"
runner = CliRunner()

MISSION = """\
from executive_engine_api import activate_behavior, execute_behavior


def runMission():
    execute_behavior('GO_TO_POINT', coordinates=[1, 1, 1])
    execute_behavior('TAKE_OF')
    activate_behavior('PAY_ATTENTION')
"""


@pytest.fixture
def project(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    shutil.copy(FIXTURES / "rules" / "AX401.yaml", tmp_path / "catalog.yaml")
    shutil.copy(DEFAULT_CATALOG, tmp_path / "behaviors.yaml")
    (tmp_path / "missions").mkdir()
    (tmp_path / "missions" / "flight.py").write_text(MISSION)
    monkeypatch.chdir(tmp_path)
    return tmp_path


def rules_of(output: str) -> list[tuple[str, int]]:
    """(rule, line) of each finding of a JSON report."""
    return [(f["rule"], f["line"]) for f in json.loads(output)["findings"]]


def verify(*args: str) -> list[tuple[str, int]]:
    result = runner.invoke(app, ["verify", *args, "-f", "json", "--min-severity", "warning"])
    assert result.exit_code in (0, 1), result.output
    return rules_of(result.output)


def test_selection_by_code_and_prefix_most_specific_wins() -> None:
    def enabled(*layers: SelectionLayer) -> set[str]:
        codes = RuleSelection(layers).enabled_codes()
        return {c for c in codes if c.startswith("AX71")} | {
            c for c in codes if c in ("AX401", "AX701")
        }

    assert enabled(SelectionLayer(select=("AX7",), ignore=("AX71",))) == {"AX701"}
    assert enabled(SelectionLayer(ignore=("AX7",), extend_select=("AX711",))) == {
        "AX401",
        "AX711",
    }
    # A later layer (the command line) starts again with its own select.
    assert enabled(SelectionLayer(select=("AX4",)), SelectionLayer(select=("AX711",))) == {"AX711"}
    # The same length: ignore wins.
    assert "AX711" not in enabled(SelectionLayer(select=("AX711",), ignore=("AX711",)))
    with pytest.raises(AeroexecError, match="unknown rule selector 'AX99'"):
        RuleSelection((SelectionLayer(select=("AX99",)),))


def test_select_ignore_and_extend_select_on_the_command_line(project: Path) -> None:
    every = verify("behaviors.yaml", "-m", "missions/flight.py")
    assert ("AX701", 6) in every and ("AX711", 5) in every and ("AX712", 7) in every
    only = verify("behaviors.yaml", "-m", "missions/flight.py", "--select", "AX71")
    assert {rule for rule, _ in only} == {"AX711", "AX712"}
    less = verify(
        "behaviors.yaml", "-m", "missions/flight.py", "--select", "AX7", "--ignore", "AX71"
    )
    assert {rule for rule, _ in less} == {"AX701"}
    back = verify(
        "behaviors.yaml",
        "-m",
        "missions/flight.py",
        "--select",
        "AX7",
        "--ignore",
        "AX71",
        "--extend-select",
        "AX712",
    )
    assert {rule for rule, _ in back} == {"AX701", "AX712"}


def test_an_unknown_selector_is_a_usage_error(project: Path) -> None:
    result = runner.invoke(app, ["verify", "catalog.yaml", "--ignore", "AX4O1"])
    assert result.exit_code == 2
    assert "unknown rule selector 'AX4O1'" in result.output


def test_statistics_count_findings_per_rule(project: Path) -> None:
    result = runner.invoke(
        app,
        ["verify", "catalog.yaml", "behaviors.yaml", "-m", "missions/flight.py", "--statistics"],
    )
    assert result.exit_code == 1
    rows = [line.split("\t") for line in result.output.splitlines()]
    counts = [int(count) for count, _, _ in rows]
    assert counts == sorted(counts, reverse=True)
    assert ["2", "AX401", "asymmetric-incompatibility"] in rows
    assert ["1", "AX711", "mission-wrong-flight-state"] in rows
    as_json = runner.invoke(
        app, ["verify", "catalog.yaml", "--statistics", "-f", "json", "--select", "AX4"]
    )
    assert json.loads(as_json.output) == [
        {"code": "AX401", "name": "asymmetric-incompatibility", "count": 2}
    ]


def test_noqa_in_a_mission_and_ignore_in_a_catalog(project: Path) -> None:
    mission = project / "missions" / "flight.py"
    mission.write_text(
        MISSION.replace("[1, 1, 1])", "[1, 1, 1])  # noqa: AX711").replace(
            "('TAKE_OF')", "('TAKE_OF')  # noqa: AX702"
        )
    )
    found = verify("behaviors.yaml", "-m", "missions/flight.py")
    assert ("AX711", 5) not in found  # suppressed on its line
    assert ("AX701", 6) in found  # a noqa for another code does not hide it
    catalog = project / "catalog.yaml"
    text = catalog.read_text()
    catalog.write_text(
        text.replace(
            "  - behavior: GO_TO  # expect AX401 at behavior",
            "  # aeroexec: ignore[AX401]\n  - behavior: GO_TO",
        )
    )
    assert verify("catalog.yaml") == [("AX401", 5)]
    result = runner.invoke(app, ["verify", "catalog.yaml"])
    assert "(1 suppressed in place)" in result.output.splitlines()[-1]
    # A noqa inside a string is text, not a comment.
    mission.write_text(MISSION.replace("('TAKE_OF')", "('TAKE_OF # noqa')"))
    assert ("AX701", 6) in verify("behaviors.yaml", "-m", "missions/flight.py")


def test_the_project_configuration_selects_and_lists_what_to_check(project: Path) -> None:
    (project / "missions" / "legacy_flight.py").write_text(MISSION)
    (project / "pyproject.toml").write_text(
        textwrap.dedent(
            """\
            [tool.aeroexec.verify]
            catalogs = ["behaviors.yaml"]
            missions = ["missions/*.py"]
            ignore = ["AX712"]
            per-file-ignores = {"missions/legacy_*.py" = ["AX7"]}
            """
        )
    )
    (project / "sub").mkdir()
    found = verify()  # bare: the project's catalogs and missions
    assert ("AX712", 7) not in found
    result = runner.invoke(app, ["verify", "-f", "json"])
    files = {f["file"] for f in json.loads(result.output)["findings"]}
    assert str(Path("missions") / "flight.py") in files  # relative, as ruff shows them
    assert not any("legacy" in file for file in files)
    # The command line's select replaces the project's; its ignore stays a layer below.
    again = runner.invoke(app, ["verify", "-f", "json", "--select", "AX712"])
    assert {f["rule"] for f in json.loads(again.output)["findings"]} == {"AX712"}


def test_a_wrong_verify_key_is_a_config_error_with_its_line(project: Path) -> None:
    (project / "pyproject.toml").write_text("[tool.aeroexec.verify]\nselekt = ['AX7']\n")
    result = runner.invoke(app, ["verify"])
    assert result.exit_code == 2
    assert "pyproject.toml:2:1: error: unknown key 'verify.selekt'" in result.output


# -- --fix and --diff -----------------------------------------------------------------------
ONE_SIDED = (
    "behavior_descriptors:\r\n"
    "  - behavior: DOCK   # the dock\r\n"
    "    timeout: 10\r\n"
    "    recurrent: no\r\n"
    "    incompatible_lists: [motion]\r\n"
    "  - behavior: GO_TO\r\n"
    "    timeout: 10\r\n"
    "\r\n"
    "    recurrent: no\r\n"
    "  # a comment that stays, \u00e9t\u00e9\r\n"
    "behavior_lists:\r\n"
    "  - list: motion\r\n"
    "    behaviors: [GO_TO, DOCK]\r\n"
    "capability_descriptors: []"  # no newline at the end
)


def test_fix_makes_a_one_sided_preemption_mutual_and_changes_nothing_else(
    project: Path,
) -> None:
    catalog = project / "one.yaml"
    catalog.write_bytes(ONE_SIDED.encode("utf-8"))
    catalog.chmod(0o640)
    shown = runner.invoke(app, ["verify", "one.yaml", "--diff"])
    assert shown.exit_code == 1
    assert "+    incompatible_lists: [motion]" in shown.output
    assert catalog.read_bytes() == ONE_SIDED.encode("utf-8")  # --diff changes nothing
    fixed = runner.invoke(app, ["verify", "one.yaml", "--fix"])
    assert fixed.exit_code == 0, fixed.output
    assert "AX401" not in fixed.output
    expected = ONE_SIDED.replace(
        "    recurrent: no\r\n  # a comment",
        "    recurrent: no\r\n    incompatible_lists: [motion]\r\n  # a comment",
    )
    assert catalog.read_bytes() == expected.encode("utf-8")
    assert catalog.stat().st_mode & 0o777 == 0o640
    again = runner.invoke(app, ["verify", "one.yaml", "--diff"])
    assert again.exit_code == 0 and again.output.startswith("aeroexec verify: note: 0 fixes")


def test_an_ambiguous_one_sided_preemption_gets_no_fix(project: Path) -> None:
    # GO_TO is preempted by DOCK through `motion`, but no list holds DOCK: which list
    # GO_TO should name is a design decision.
    before = (project / "catalog.yaml").read_bytes()
    result = runner.invoke(app, ["verify", "catalog.yaml", "--fix"])
    assert "AX401" in result.output
    assert (project / "catalog.yaml").read_bytes() == before


def test_fix_indents_a_misindented_parameter_key_byte_for_byte(project: Path) -> None:
    source = (FIXTURES / "tasks" / "AX803.yaml").read_bytes()
    catalog = project / "tasks.yaml"
    catalog.write_bytes(source)
    result = runner.invoke(app, ["verify", "tasks.yaml", "--fix"])
    assert "AX803" not in result.output, result.output
    expected = source.replace(
        b"  - parameter: path\n  allowed_values: point_list",
        b"  - parameter: path\n    allowed_values: point_list",
    )
    assert expected != source
    assert catalog.read_bytes() == expected


PREEMPTOR = """\
behavior_descriptors:
  - behavior: DOCK
    timeout: 10
    incompatible_lists: [motion]
  - behavior: PARK
    timeout: 10
    incompatible_lists: [motion]
  - behavior: GO_TO
    timeout: 10
    incompatible_lists: [motion]
  - behavior: SPIN
    timeout: 10
    incompatible_lists: [motion]
behavior_lists:
  - list: motion
    behaviors: [GO_TO, SPIN]  # the movers
capability_descriptors: []
"""


@pytest.mark.parametrize(
    ("members", "fixed"),
    [
        (
            "    behaviors: [GO_TO, SPIN]  # the movers\n",
            "    behaviors: [GO_TO, SPIN, DOCK, PARK]  # the movers\n",
        ),
        (
            "    behaviors:\n      - GO_TO\n      - SPIN\n",
            "    behaviors:\n      - GO_TO\n      - SPIN\n      - DOCK\n      - PARK\n",
        ),
    ],
    ids=["flow", "block"],
)
def test_fix_adds_a_one_sided_preemptor_to_its_list(
    project: Path, members: str, fixed: str
) -> None:
    # DOCK and PARK preempt the movers through `motion`, which they are not in; every
    # mover names `motion`: joining it makes the preemption mutual. The two fixes touch
    # the same line: --fix applies the second in a second pass.
    source = PREEMPTOR.replace("    behaviors: [GO_TO, SPIN]  # the movers\n", members)
    catalog = project / "movers.yaml"
    catalog.write_text(source)
    result = runner.invoke(app, ["verify", "movers.yaml", "--fix"])
    assert "AX401" not in result.output, result.output
    assert "2 fixes applied in 1 file" in result.output
    assert catalog.read_text() == source.replace(members, fixed)


UNUSED_MISSION = """\
from executive_engine_api import execute_behavior


def runMission():
    execute_behavior('TAKE_OFF')  # noqa: AX711
    execute_behavior('TAKE_OF')  # noqa: AX701, AX999
    # noqa
    execute_behavior('LAND')
    execute_behavior('LAND')  # why  # noqa: AX001
"""


def test_an_unused_suppression_is_reported_and_fix_removes_it(project: Path) -> None:
    # As ruff's RUF100: a noqa that silences nothing, a code that names no rule, a
    # blanket noqa (alone on its line: it covers the next one) with nothing to silence.
    # One that silences something stays; one naming AX001 keeps itself.
    mission = project / "missions" / "flight.py"
    mission.write_text(UNUSED_MISSION)
    result = runner.invoke(app, ["verify", "behaviors.yaml", "-m", "missions/flight.py"])
    unused = [line for line in result.output.splitlines() if " AX001 " in line]
    assert unused == [
        "missions/flight.py:5:35: warning AX001 unused suppression: AX711 silences no "
        "finding on this line",
        "missions/flight.py:6:34: warning AX001 unused suppression: AX999 is not a rule code",
        "missions/flight.py:7:5: warning AX001 unused suppression: a blanket one that "
        "silences no finding on this line or the next",
    ]
    assert ("AX701", 6) not in verify("behaviors.yaml", "-m", "missions/flight.py")
    ignored = verify("behaviors.yaml", "-m", "missions/flight.py", "--ignore", "AX001")
    assert not [rule for rule, _ in ignored if rule == "AX001"]
    fixed = runner.invoke(app, ["verify", "behaviors.yaml", "-m", "missions/flight.py", "--fix"])
    assert "3 fixes applied in 1 file" in fixed.output, fixed.output
    assert mission.read_text() == UNUSED_MISSION.replace("  # noqa: AX711", "").replace(
        "AX701, AX999", "AX701"
    ).replace("    # noqa\n", "")
    assert " AX001 " not in fixed.output
    # In a catalog: only the unused code goes, the comment still silences AX401.
    catalog = project / "catalog.yaml"
    catalog.write_text(
        catalog.read_text().replace(
            "  - behavior: GO_TO  # expect AX401 at behavior",
            "  - behavior: GO_TO  # aeroexec: ignore[AX401, AX2]",
        )
    )
    assert ("AX001", 6) in verify("catalog.yaml")
    runner.invoke(app, ["verify", "catalog.yaml", "--fix"])
    assert "  - behavior: GO_TO  # aeroexec: ignore[AX401]\n" in catalog.read_text()
    assert ("AX001", 6) not in verify("catalog.yaml")


CHAIN = """\
behavior_descriptors:
  - behavior: DOCK
    timeout: 10
    recurrent: no
    incompatible_lists: [motion]
    capabilities: [ARM]
  - behavior: GO_TO
    timeout: 10
    recurrent: no
    capabilities: [WHEELS]  # aeroexec: ignore[AX304]
behavior_lists:
  - list: motion
    behaviors: [GO_TO]
  - list: docking
    behaviors: [DOCK]
capability_descriptors:
  - capability: ARM
    active_by_default: no
    processes: [arm]
    incompatible_capabilities: [WHEELS]
  - capability: WHEELS
    active_by_default: no
    processes: [wheels]
    incompatible_capabilities: [ARM]
"""


def test_diff_and_fix_run_the_fixes_a_fix_makes_possible(project: Path) -> None:
    # Pass 1: GO_TO, preempted one-sidedly by DOCK, names DOCK's list (AX401's fix);
    # that makes the conflict declared, so the ignore[AX304] on GO_TO's line silences
    # nothing any more: pass 2 removes it (AX001's fix). --diff shows both passes'
    # result and writes nothing; --fix writes exactly that.
    catalog = project / "chain.yaml"
    catalog.write_text(CHAIN)
    fixed = CHAIN.replace(
        "    capabilities: [WHEELS]  # aeroexec: ignore[AX304]\n",
        "    capabilities: [WHEELS]\n    incompatible_lists: [docking]\n",
    )
    shown = runner.invoke(app, ["verify", "chain.yaml", "--diff"])
    assert shown.exit_code == 1
    assert "-    capabilities: [WHEELS]  # aeroexec: ignore[AX304]\n" in shown.output
    assert "+    capabilities: [WHEELS]\n+    incompatible_lists: [docking]\n" in shown.output
    assert "2 fixes in 1 file would apply (2 passes" in shown.output
    assert catalog.read_text() == CHAIN
    result = runner.invoke(app, ["verify", "chain.yaml", "--fix"])
    assert result.exit_code == 0, result.output
    assert catalog.read_text() == fixed
    assert "2 fixes applied in 1 file" in result.output


def test_diff_shows_fixes_of_the_same_line_from_later_passes(project: Path) -> None:
    # DOCK and PARK both join `motion`: the second fix touches the same line and waits
    # for a second pass, which --diff runs too (in memory).
    catalog = project / "movers.yaml"
    catalog.write_text(PREEMPTOR)
    shown = runner.invoke(app, ["verify", "movers.yaml", "--diff"])
    assert "+    behaviors: [GO_TO, SPIN, DOCK, PARK]  # the movers\n" in shown.output
    assert catalog.read_text() == PREEMPTOR
