"""`aeroexec verify` from the command line: formats, exit codes, bad input."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import jsonschema
import pytest
from typer.testing import CliRunner

from aeroexec.catalog import DEFAULT_CATALOG, THESIS_CATALOG
from aeroexec.cli import app
from aeroexec.verifier import all_rules

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "verifier"
RULES = FIXTURES / "rules"
MISSIONS = FIXTURES / "missions"
SCHEMA = json.loads((FIXTURES / "sarif-schema-2.1.0.json").read_text(encoding="utf-8"))
ROOT = Path(__file__).resolve().parent.parent

runner = CliRunner()
TEXT_LINE = re.compile(
    r"^(?P<file>[^:]+):(?P<line>\d+):(?P<col>\d+): (error|warning|info) AX\d{3} .+$"
)


def run(*args: str) -> tuple[int, str, str]:
    result = runner.invoke(app, ["verify", *args])
    return result.exit_code, result.stdout, result.stderr


def assert_one_line_error(code: int, out: str, err: str, *fragments: str) -> None:
    assert code == 2
    assert out == ""
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    for fragment in fragments:
        assert fragment in lines[0]


# -- text -----------------------------------------------------------------------------------
def test_text_output_is_compiler_style_with_a_summary() -> None:
    code, out, _ = run(str(THESIS_CATALOG))
    assert code == 1
    *findings, summary = out.strip().splitlines()
    assert findings
    for line in findings:
        assert TEXT_LINE.match(line), line
    assert f"{THESIS_CATALOG}:116:25: error AX202 list rotation_behaviors: LOOK_AT_POINT" in out
    assert summary.startswith("2 errors, 4 warnings, 0 infos in 1 file")
    assert "below --min-severity not shown" in summary
    assert "\x1b[" not in out  # no color when not on a terminal


def test_min_severity_info_shows_infos_and_error_hides_warnings() -> None:
    _, everything, _ = run(str(THESIS_CATALOG), "--min-severity", "info")
    assert " info AX109 " in everything
    _, errors_only, _ = run(str(THESIS_CATALOG), "--min-severity", "error")
    assert " warning " not in errors_only
    assert errors_only.count(" error AX202 ") == 2


def test_machine_formats_keep_infos_by_default() -> None:
    _, out, _ = run(str(THESIS_CATALOG), "--format", "json")
    document = json.loads(out)
    assert document["summary"]["infos"] > 0
    assert any(f["rule"] == "AX109" for f in document["findings"])
    _, out, _ = run(str(THESIS_CATALOG), "--format", "json", "--min-severity", "warning")
    assert json.loads(out)["summary"]["infos"] == 0


def test_catalog_pattern_matching_nothing(tmp_path: Path) -> None:
    pattern = str(tmp_path / "*.yaml")
    assert_one_line_error(*run(pattern), "no catalog matches this pattern")


def test_color_always() -> None:
    _, out, _ = run(str(THESIS_CATALOG), "--color", "always")
    assert "\x1b[" in out


def test_clean_catalog_exits_0() -> None:
    code, out, _ = run(str(DEFAULT_CATALOG))
    assert code == 0
    assert out.strip().splitlines()[-1].startswith("0 errors, 0 warnings")


def test_strict_fails_on_warnings() -> None:
    warning_only = RULES / "AX601.yaml"
    assert run(str(warning_only))[0] == 0
    assert run(str(warning_only), "--strict")[0] == 1
    # --strict counts warnings even when --min-severity hides them.
    assert run(str(warning_only), "--strict", "--min-severity", "error")[0] == 1


def test_witness_lines() -> None:
    _, plain, _ = run(str(RULES / "AX304.yaml"))
    assert "witness:" not in plain
    _, out, _ = run(str(RULES / "AX304.yaml"), "--witness")
    assert (
        "    witness: activate GO_TO, then activate FOLLOW: the activation of FOLLOW is "
        "rejected" in out.splitlines()
    )
    _, out, _ = run(str(RULES / "AX302.yaml"), "--witness")
    assert "    witness: initiation fails before any activation" in out


def test_several_catalogs_and_a_quoted_glob(tmp_path: Path) -> None:
    for name in ("AX201.yaml", "AX203.yaml"):
        shutil.copy(RULES / name, tmp_path / name)
    code, out, _ = run(str(tmp_path / "*.yaml"))
    assert code == 1
    assert "AX201.yaml:5:33: error AX201" in out
    assert "AX203.yaml:5:27: error AX203" in out
    assert " in 2 files" in out


def test_missions_are_checked_against_every_catalog() -> None:
    mission = str(MISSIONS / "AX701.py")
    code, out, _ = run(str(MISSIONS / "catalog.yaml"), "--mission", mission)
    assert code == 1
    assert f"{mission}:7:25: error AX701 executeBehavior('TAKE_OF'): unknown behavior" in out
    _, two, _ = run(str(MISSIONS / "catalog.yaml"), str(DEFAULT_CATALOG), "-m", mission)
    assert two.count("executeBehavior('TAKE_OF')") == 2
    assert f"[catalog {DEFAULT_CATALOG}]" in two


def test_mission_glob() -> None:
    code, out, _ = run(str(MISSIONS / "catalog.yaml"), "--mission", str(MISSIONS / "AX70[45].py"))
    assert code == 1
    assert {"AX704", "AX705"} == set(re.findall(r" error (AX7\d\d) ", out))


# -- json -----------------------------------------------------------------------------------
def test_json_shape() -> None:
    code, out, _ = run(str(RULES / "AX304.yaml"), "--format", "json", "--min-severity", "info")
    assert code == 1
    document = json.loads(out)
    assert set(document) == {"findings", "summary", "inputErrors"}
    assert document["inputErrors"] == []
    assert set(document["summary"]) == {"errors", "warnings", "infos"}
    keys = {
        "rule",
        "severity",
        "message",
        "file",
        "line",
        "column",
        "subjects",
        "witness",
        "path",
        "related",
    }
    for finding in document["findings"]:
        assert set(finding) == keys
        assert finding["severity"] in ("error", "warning", "info")
        assert finding["line"] >= 1 and finding["column"] >= 1
    counts = {
        s: sum(f["severity"] == s for f in document["findings"])
        for s in ("error", "warning", "info")
    }
    assert document["summary"] == {
        "errors": counts["error"],
        "warnings": counts["warning"],
        "infos": counts["info"],
    }
    ax304 = [f for f in document["findings"] if f["rule"] == "AX304"]
    assert ax304[1]["witness"] == [
        {"activate": "GO_TO", "arguments": {}},
        {"activate": "FOLLOW", "arguments": {}},
    ]
    assert ax304[1]["subjects"] == ["GO_TO", "FOLLOW", "FLIGHT_CONTROL", "SERVOING"]


# -- sarif ----------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "args",
    [
        (str(THESIS_CATALOG), "--min-severity", "info"),
        (str(RULES / "AX304.yaml"),),
        (str(RULES / "AX101.yaml"),),
        (str(MISSIONS / "catalog.yaml"), "-m", str(MISSIONS / "AX703.py")),
    ],
    ids=["thesis", "witness", "loader", "mission"],
)
def test_sarif_validates_against_the_2_1_0_schema(args: tuple[str, ...]) -> None:
    code, out, _ = run(*args, "--format", "sarif")
    assert code == 1
    document = json.loads(out)
    jsonschema.Draft4Validator(SCHEMA).validate(document)
    assert document["version"] == "2.1.0"
    [run_] = document["runs"]
    rules = run_["tool"]["driver"]["rules"]
    assert [r["id"] for r in rules] == [r.code for r in all_rules()]
    assert run_["results"]
    for result in run_["results"]:
        assert rules[result["ruleIndex"]]["id"] == result["ruleId"]
        assert result["level"] in ("error", "warning", "note")
        location = result["locations"][0]["physicalLocation"]
        assert location["region"]["startLine"] >= 1
        artifact = location["artifactLocation"]
        if artifact.get("uriBaseId") == "%SRCROOT%":
            base = run_["originalUriBaseIds"]["%SRCROOT%"]["uri"]
            assert (Path(base.removeprefix("file://")) / artifact["uri"]).exists()
        else:
            assert artifact["uri"].startswith("file:///")


def test_sarif_schema_rejects_a_broken_document() -> None:
    _, out, _ = run(str(RULES / "AX304.yaml"), "--format", "sarif")
    document = json.loads(out)
    document["runs"][0]["results"][0]["level"] = "fatal"
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.Draft4Validator(SCHEMA).validate(document)


# -- github ---------------------------------------------------------------------------------
def test_github_annotations() -> None:
    code, out, _ = run(str(THESIS_CATALOG), "--format", "github")
    assert code == 1
    lines = out.strip().splitlines()
    assert (
        f"::error file={THESIS_CATALOG},line=113,col=9,title=AX202::list motion_behaviors: "
        "VISUAL_SERVOING is a capability, not a behavior"
    ) in lines
    assert all(
        re.match(r"^::(error|warning|notice) file=[^,]+,line=\d+,col=\d+,title=AX\d{3}::", x)
        for x in lines
    )


def test_github_escapes_properties_and_data() -> None:
    from aeroexec.catalog.model import Severity
    from aeroexec.verifier import Finding
    from aeroexec.verifier.report.github import format_finding

    finding = Finding("AX201", Severity.WARNING, "50% done\nnext", "a,b:c.yaml", 3, 4)
    assert format_finding(finding) == (
        "::warning file=a%2Cb%3Ac.yaml,line=3,col=4,title=AX201::50%25 done%0Anext"
    )


# -- explain --------------------------------------------------------------------------------
def test_explain_a_loader_code_and_a_rule() -> None:
    code, out, _ = run("--explain", "AX104")
    assert code == 0
    assert out.startswith("AX104 unknown-tag (warning;")
    code, out, _ = run("--explain", "ax304")
    assert code == 0
    assert "undeclared-capability-conflict" in out
    assert "witness" in out


def test_explain_unknown_code() -> None:
    assert_one_line_error(*run("--explain", "AX999"), "unknown rule code 'AX999'")


# -- bad input: one stderr line, exit 2 ------------------------------------------------------
def test_missing_catalog(tmp_path: Path) -> None:
    missing = tmp_path / "nope.yaml"
    assert_one_line_error(*run(str(missing)), f"{missing}: error: no such file")


def test_invalid_yaml(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("behavior_descriptors:\n  - behavior: [A\n", encoding="utf-8")
    assert_one_line_error(*run(str(bad)), f"{bad}:", "error: invalid YAML")


def test_task_based_catalog_is_verified() -> None:
    task = (
        Path(__file__).resolve().parent
        / "fixtures"
        / "verifier_catalogs"
        / "cvar-upm+coordinator_cbc__behavior_coordinator_src_test_behavior_catalog_missing_task"
        "__4edaaf8.yaml"
    )
    code, out, err = run(str(task), "--witness")
    assert (code, err) == (1, "")
    assert f"{task}:111:11: error AX812 QUADROTOR_MPC_MOTION_CONTROL requires task " in out
    assert "    witness: start task MPC_MOTION_CONTROL: the start of MPC_MOTION_CONTROL is " in out


def test_mission_syntax_error(tmp_path: Path) -> None:
    mission = tmp_path / "appendix_c_original.py"
    mission.write_text((MISSIONS / "syntax_error.py.txt").read_text(encoding="utf-8"))
    text = mission.read_text(encoding="utf-8").splitlines()[4]
    column = text.index("angle:-90") + len("angle") + 1  # the ':' Python stops at
    code, out, err = run(str(THESIS_CATALOG), "--mission", str(mission))
    assert_one_line_error(
        code, "", err, f"{mission}:5:{column}: error: not valid Python: invalid syntax"
    )
    # The catalog, which could be read, is verified all the same.
    assert f"{THESIS_CATALOG}:116:25: error AX202" in out
    assert out.strip().splitlines()[-1].endswith("not shown); 1 input could not be read")


def test_mission_pattern_matching_nothing(tmp_path: Path) -> None:
    pattern = str(tmp_path / "*.py")
    code, out, err = run(str(THESIS_CATALOG), "--mission", pattern)
    assert_one_line_error(code, "", err, "no mission file matches")
    assert " error AX202 " in out


def test_unknown_format_and_severity() -> None:
    assert_one_line_error(
        *run(str(THESIS_CATALOG), "--format", "xml"),
        "invalid value for --format: 'xml' is not one of 'text', 'json', 'sarif', 'github'",
    )
    assert_one_line_error(
        *run(str(THESIS_CATALOG), "--min-severity", "fatal"),
        "invalid value for --min-severity: 'fatal' is not one of 'info', 'warning', 'error'",
    )


def test_no_catalog() -> None:
    assert_one_line_error(*run(), "no catalog given")


def test_help_has_an_example() -> None:
    result = runner.invoke(app, ["verify", "--help"])
    assert result.exit_code == 0
    assert "aeroexec verify catalog/default.yaml" in result.stdout
    assert "Exit codes" in result.stdout


def test_python_module_entry_point_prints_no_traceback(tmp_path: Path) -> None:
    import subprocess
    import sys

    bad = tmp_path / "bad.yaml"
    bad.write_text("a: [\n", encoding="utf-8")
    result = subprocess.run(
        [sys.executable, "-m", "aeroexec", "verify", str(bad)],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=False,
    )
    assert result.returncode == 2
    assert result.stdout == ""
    assert len(result.stderr.strip().splitlines()) == 1
    assert "invalid YAML" in result.stderr


# -- many inputs, one verdict (an unreadable input does not stop the others) ---------------
def _glob_with_a_broken_catalog(tmp_path: Path) -> tuple[str, Path]:
    for name in ("AX201.yaml", "AX203.yaml"):
        shutil.copy(RULES / name, tmp_path / name)
    broken = tmp_path / "AX202_broken.yaml"
    broken.write_text("behavior_descriptors:\n  - behavior: [A\n", encoding="utf-8")
    return str(tmp_path / "*.yaml"), broken


def test_an_unreadable_catalog_in_a_glob_does_not_stop_the_others(tmp_path: Path) -> None:
    pattern, broken = _glob_with_a_broken_catalog(tmp_path)
    code, out, err = run(pattern)
    assert code == 2
    assert "AX201.yaml:5:33: error AX201" in out
    assert "AX203.yaml:5:27: error AX203" in out
    assert out.strip().splitlines()[-1].endswith("not shown); 1 input could not be read")
    assert " in 2 files " in out
    [line] = err.strip().splitlines()
    assert line.startswith(f"{broken}:3:1: error: invalid YAML")


def test_sarif_with_an_unreadable_input_is_valid_and_holds_the_other_results(
    tmp_path: Path,
) -> None:
    pattern, _ = _glob_with_a_broken_catalog(tmp_path)
    code, out, _ = run(pattern, "--format", "sarif")
    assert code == 2
    document = json.loads(out)
    jsonschema.Draft4Validator(SCHEMA).validate(document)
    [run_] = document["runs"]
    [invocation] = run_["invocations"]
    assert invocation["executionSuccessful"] is False
    [notification] = invocation["toolExecutionNotifications"]
    assert notification["level"] == "error"
    assert notification["message"]["text"].startswith("invalid YAML")
    location = notification["locations"][0]["physicalLocation"]
    assert location["artifactLocation"]["uri"].endswith("AX202_broken.yaml")
    assert location["region"] == {"startLine": 3, "startColumn": 1}
    files = {
        r["locations"][0]["physicalLocation"]["artifactLocation"]["uri"] for r in run_["results"]
    }
    assert {Path(f).name for f in files} == {"AX201.yaml", "AX203.yaml"}


def test_github_reports_an_unreadable_input_as_an_error_annotation(tmp_path: Path) -> None:
    pattern, broken = _glob_with_a_broken_catalog(tmp_path)
    code, out, _ = run(pattern, "--format", "github")
    assert code == 2
    escaped = str(broken).replace(":", "%3A").replace(",", "%2C")
    assert f"::error file={escaped},line=3,col=1,title=unreadable input::invalid YAML" in out
    assert "title=AX201::" in out


def test_sarif_rules_link_to_their_paragraph_of_the_docs() -> None:
    _, out, _ = run(str(RULES / "AX304.yaml"), "--format", "sarif")
    rules = json.loads(out)["runs"][0]["tool"]["driver"]["rules"]
    docs = (ROOT / "docs" / "rules.md").read_text(encoding="utf-8")
    for rule in rules:
        uri = rule["helpUri"]
        page, _, anchor = uri.partition("#")
        assert page == (ROOT / "docs" / "rules.md").as_uri()
        assert anchor == rule["id"].lower()
        assert f"\n### {rule['id']}\n" in docs


def test_sarif_fingerprints_are_unique_and_survive_line_shifts(tmp_path: Path) -> None:
    catalog = tmp_path / "c.yaml"
    text = (RULES / "AX202.yaml").read_text(encoding="utf-8")
    catalog.write_text(text, encoding="utf-8")
    results = json.loads(run(str(catalog), "--format", "sarif")[1])["runs"][0]["results"]
    catalog.write_text("# moved\n\n" + text, encoding="utf-8")
    shifted = json.loads(run(str(catalog), "--format", "sarif")[1])["runs"][0]["results"]
    prints = [r["partialFingerprints"]["aeroexecFinding/v1"] for r in results]
    assert len(set(prints)) == len(prints)
    assert [r["partialFingerprints"] for r in shifted] == [
        r["partialFingerprints"] for r in results
    ]
    lines = [r["locations"][0]["physicalLocation"]["region"]["startLine"] for r in results]
    moved = [r["locations"][0]["physicalLocation"]["region"]["startLine"] for r in shifted]
    assert moved == [line + 2 for line in lines]


# -- the vehicle's limits come from the world description ----------------------------------
def test_reach_checks_use_the_limits_of_the_world_given() -> None:
    fixture = str(RULES / "AX604.yaml")
    _, slow, _ = run(fixture)
    assert slow.count(" warning AX604 ") == 2
    assert "2 m/s horizontal, 1 m/s vertical, 2 m/s² (default world)" in slow
    code, fast, _ = run(fixture, "--world", str(FIXTURES / "worlds" / "fast.yaml"))
    assert code == 0
    assert " AX604 " not in fast  # 141 m at 10 m/s and 100 m at 5 m/s fit in 30 s


def test_an_unreadable_world_is_one_line_and_exit_2(tmp_path: Path) -> None:
    world = tmp_path / "world.yaml"
    world.write_text("vehicle:\n  max_horizontal_speed: fast\n", encoding="utf-8")
    assert_one_line_error(*run(str(RULES / "AX604.yaml"), "-w", str(world)), f"{world}:2:")
