"""docs/ci.md: the workflow is valid YAML with the steps it promises, and the replay
command it runs works on this repository's recordings."""

from __future__ import annotations

import re
import shlex
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest
import yaml
from test_replay_support import REPO
from typer.testing import CliRunner

from aeroexec.cli import app

DOC = REPO / "docs" / "ci.md"


def workflow() -> dict[str, Any]:
    blocks = re.findall(r"```yaml\n(.*?)```", DOC.read_text(encoding="utf-8"), re.S)
    # The first block is the workflow; the shard matrix that follows: test_fleet_docs.py.
    document = yaml.safe_load(blocks[0])
    assert isinstance(document, dict)
    return document


def steps(job: str) -> list[dict[str, Any]]:
    return workflow()["jobs"][job]["steps"]


def run_text(job: str, step_id: str) -> str:
    step = next(s for s in steps(job) if s.get("id") == step_id)
    return step["run"]


def test_workflow_verifies_with_sarif_upload() -> None:
    assert "aeroexec verify catalog/*.yaml" in run_text("verify", "verify")
    assert "--format sarif > verify.sarif" in run_text("verify", "verify")
    uses = [s.get("uses", "") for s in steps("verify")]
    assert any(u.startswith("github/codeql-action/upload-sarif@") for u in uses)
    assert workflow()["jobs"]["verify"]["permissions"]["security-events"] == "write"


def test_workflow_replays_with_junit_and_publishes_it() -> None:
    text = run_text("replay", "replay")
    assert "aeroexec replay recordings/" in text
    assert "--check" in text and "--format junit" in text and "> replay.xml" in text
    publishing = [s for s in steps("replay") if s.get("if") == "always()"]
    assert {s["uses"].split("@")[0] for s in publishing} == {
        "mikepenz/action-junit-report",
        "actions/upload-artifact",
    }
    assert steps("replay")[-1]["if"] == "steps.replay.outputs.status != '0'"


def test_the_documented_replay_command_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    line = run_text("replay", "replay").split("aeroexec ", 1)[1].replace("\\\n", " ")
    args = shlex.split(line.split(">")[0])
    monkeypatch.chdir(REPO)
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.stdout + result.stderr
    (suite,) = ET.fromstring(result.stdout).findall("testsuite")
    names = [case.get("name") for case in suite.findall("testcase")]
    assert names == sorted(
        str(Path("recordings") / p.name) for p in (REPO / "recordings").glob("*.mcap")
    )
    assert suite.get("failures") == "0"
