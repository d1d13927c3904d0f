"""The small surprises of issue 19, one by one: -q, the old spellings, the rule listing,
mavsim's counts, the command named in every error line."""

from __future__ import annotations

import json
import socket
from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.recording import open_recording
from aeroexec.verifier.registry import all_rules

runner = CliRunner()

LOUD_MISSION = """\
import executive_engine_api as api

def runMission():
    print("hello from the mission")
    api.executeBehavior('TAKE_OFF')
    api.executeBehavior('LAND')
"""


@pytest.fixture
def mission(tmp_path: Path) -> Path:
    path = tmp_path / "loud.py"
    path.write_text(LOUD_MISSION)
    return path


def test_quiet_leaves_only_the_summary_even_of_a_mission_that_prints(mission: Path) -> None:
    loud = runner.invoke(app, ["run", str(mission)])
    assert loud.exit_code == 0, loud.output
    assert "hello from the mission" in loud.stdout
    assert "start    TAKE_OFF" in loud.stdout
    quiet = runner.invoke(app, ["run", str(mission), "-q"])
    assert quiet.exit_code == 0, quiet.output
    assert "hello from the mission" not in quiet.output
    assert "start    TAKE_OFF" not in quiet.stdout
    summary = quiet.stdout.splitlines()
    assert summary[0] == "Behaviors" and summary[-1].startswith("2 activations: 2 GOAL_ACHIEVED")


def test_an_old_spelling_still_works_and_says_what_replaced_it(
    mission: Path, tmp_path: Path
) -> None:
    old = tmp_path / "old.mcap"
    result = runner.invoke(app, ["run", str(mission), "-q", "-r", str(old)])
    assert result.exit_code == 0, result.output
    assert result.stderr == "aeroexec run: warning: -r/--record is deprecated; use -o/--output\n"
    assert open_recording(old).complete
    both = runner.invoke(app, ["run", str(mission), "-o", "a.mcap", "--record", "b.mcap"])
    assert both.exit_code == 2
    assert both.stderr == (
        "aeroexec run: error: give -o/--output or -r/--record (its old spelling), not both\n"
    )


@pytest.mark.parametrize(
    ("args", "old", "new"),
    [
        (["view", "missing.mcap", "--save", "x.rrd"], "--save", "-o/--output"),
        (["replay", "missing.mcap", "--out-dir", "replays"], "--out-dir", "--output-dir"),
    ],
)
def test_the_other_old_spellings_are_read_as_the_new_ones(
    args: list[str], old: str, new: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, args)
    lines = result.stderr.splitlines()
    assert lines[0] == f"aeroexec {args[0]}: warning: {old} is deprecated; use {new}"
    # Parsed, then the command ran and found the input missing (not a usage error).
    assert result.exit_code == 2 and "missing.mcap" in lines[-1]
    assert "no such option" not in result.stderr


def test_verify_lists_its_rules() -> None:
    text = runner.invoke(app, ["verify", "--list-rules"])
    assert text.exit_code == 0
    lines = text.stdout.splitlines()
    rules = all_rules()
    for rule in rules:
        severity = rule.severity.value if rule.severity else "varies"
        assert f"  {rule.code}  {severity:<7}  {rule.name}" in lines
    assert "References" in lines and "Start order" in lines
    assert lines[-1] == f"{len(rules)} rules; `aeroexec verify --explain CODE` documents one."
    listed = json.loads(runner.invoke(app, ["verify", "--list-rules", "-f", "json"]).stdout)
    assert [r["code"] for r in listed["rules"]] == [r.code for r in rules]
    assert all(r["doc"] for r in listed["rules"])
    refused = runner.invoke(app, ["verify", "--list-rules", "-f", "sarif"])
    assert refused.exit_code == 2
    assert refused.stderr == "aeroexec verify: error: --list-rules prints text or json, not sarif\n"


def _free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@pytest.mark.parametrize("tail", [False, True])
def test_mavsim_stats_are_message_counts_and_the_tail_only_on_request(
    tmp_path: Path, tail: bool
) -> None:
    stats = tmp_path / "stats.json"
    args = ["mavsim", "--duration", "0.5", "--heartbeat-hz", "20", "--stats", str(stats)]
    args += ["--connect", f"udpout:127.0.0.1:{_free_udp_port()}"]
    result = runner.invoke(app, [*args, *(["--stats-tail"] if tail else [])])
    assert result.exit_code == 0, result.output
    counts = json.loads(stats.read_text())
    assert counts["sent"]["HEARTBEAT"] >= 5
    assert ("tail" in counts) is tail
    if tail:
        assert [entry[1] for entry in counts["tail"]].count("HEARTBEAT") == counts["sent"][
            "HEARTBEAT"
        ]
    else:
        assert stats.stat().st_size < 4096


def test_every_error_line_names_its_command(tmp_path: Path) -> None:
    result = runner.invoke(app, ["layout"])
    assert result.stderr == (
        "aeroexec layout: error: choose the viewer the layout is for: --foxglove\n"
    )
    result = runner.invoke(app, ["catalog", "show", "--format", "yaml", "c.yaml"])
    assert result.stderr.startswith("aeroexec catalog show: error: invalid value for --format: ")
