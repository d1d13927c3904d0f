"""Start-up: a command imports only what it runs (issue 17).

`aeroexec` loads a command's module when that command is used, and lists the commands
in `--help` from a table (aeroexec/cli/commands.py) that must say what the modules say.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import typer.core
import typer.main
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.cli.commands import COMMANDS

ROOT = Path(__file__).resolve().parent.parent
#: Libraries no start-up should pay for unless its command needs them.
HEAVY = ("networkx", "rosbags", "pymavlink", "rerun", "mcap", "pydantic", "jsonschema", "rich")

PROBE = """
import contextlib, io, json, sys
sys.argv = ["aeroexec", *json.loads(sys.argv[1])]
from aeroexec.cli import main
out = io.StringIO()
try:
    with contextlib.redirect_stdout(out):
        main()
except SystemExit:
    pass
print(json.dumps({"out": out.getvalue(), "modules": sorted(sys.modules)}))
"""


def _modules_after(*args: str) -> tuple[str, list[str]]:
    """(stdout, imported modules) of `aeroexec ARGS` in a fresh interpreter."""
    done = subprocess.run(
        [sys.executable, "-c", PROBE, json.dumps(list(args))],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    )
    result = json.loads(done.stdout.strip().splitlines()[-1])
    return result["out"], result["modules"]


@pytest.mark.parametrize("args", [["--version"], ["--help"]])
def test_version_and_help_import_no_command(args: list[str]) -> None:
    out, modules = _modules_after(*args)
    assert out.startswith("aeroexec ") or "Commands:" in out
    commands = [m for m in modules if m.startswith("aeroexec.cli.") and m.endswith("_cmd")]
    assert commands == []
    assert [m for m in HEAVY if m in modules] == []


def test_verify_imports_its_command_only() -> None:
    out, modules = _modules_after("verify", "catalog/default.yaml")
    assert "0 errors" in out
    commands = [m for m in modules if m.startswith("aeroexec.cli.") and m.endswith("_cmd")]
    assert commands == ["aeroexec.cli.verify_cmd"]
    # The verifier's graph questions are networkx's (the project's rule), so verify
    # imports it; nothing else heavy: not pydantic (the command line's plain values are
    # read without it, aeroexec/cli/command.py).
    assert "networkx" in modules
    assert [m for m in HEAVY if m in modules and m != "networkx"] == []
    # A catalog without missions, tasks or behaviors of its own: no executive core, no
    # simulator, no mission checks, no task rules, no other report format.
    unused = (
        "typer._adapters",
        "aeroexec.executive.executive",
        "aeroexec.vehicles.sim",
        "aeroexec.verifier.missions",
        "aeroexec.verifier.mission_run",
        "aeroexec.verifier.task_rules",
        "aeroexec.verifier.witness_run",
        "aeroexec.verifier.report.sarif",
    )
    assert [m for m in unused if m in modules] == []


def test_the_rules_of_each_kind_are_all_found_when_only_that_kind_is_asked_for() -> None:
    probe = (
        "import json, sys\n"
        "from aeroexec.verifier.registry import all_rules\n"
        "kind = sys.argv[1]\n"
        "first = [r.code for r in all_rules(kind)]\n"
        "every = [r.code for r in all_rules() if r.kind == kind]\n"
        "print(json.dumps([first, every]))\n"
    )
    for kind in ("loader", "catalog", "code", "mission", "task"):
        done = subprocess.run(
            [sys.executable, "-c", probe, kind],
            cwd=ROOT,
            capture_output=True,
            text=True,
            check=True,
        )
        first, every = json.loads(done.stdout)
        assert first and first == every, kind


def test_help_lists_every_command_as_the_loaded_commands_say() -> None:
    lazy = CliRunner().invoke(app, ["--help"], terminal_width=100).output
    group = typer.main.get_command(app)
    assert list(group.list_commands(None)) == list(COMMANDS)  # type: ignore[arg-type]
    for name, entry in COMMANDS.items():
        command = group.commands[name]  # type: ignore[attr-defined]
        for limit in (40, 70, 200):
            summary = typer.core.TyperCommand(name=name, help=entry.summary)
            assert summary.get_short_help_str(limit) == command.get_short_help_str(limit), name
    # Every command is now loaded: the listing is built from the commands themselves.
    assert CliRunner().invoke(app, ["--help"], terminal_width=100).output == lazy


def test_every_command_module_registers_its_command() -> None:
    group = typer.main.get_command(app)
    for name, entry in COMMANDS.items():
        command = group.commands[name]  # type: ignore[attr-defined]
        # A group (catalog show, report merge): its subcommands are the module's.
        parts = list(getattr(command, "commands", {}).values()) or [command]
        for part in parts:
            callback = getattr(part, "callback", None)
            module = getattr(callback, "__module__", "") if callback else ""
            assert module == f"aeroexec.cli.{entry.module}", name


def test_unknown_command_is_suggested_without_loading_everything() -> None:
    result = CliRunner().invoke(app, ["verfy"])
    assert result.exit_code == 2
    assert "(did you mean 'verify'?)" in result.output


def test_the_behaviors_record_has_one_name() -> None:
    from aeroexec.plugins.manifest import METADATA_NAME
    from aeroexec.recording.schemas import CODE_METADATA_NAME

    assert METADATA_NAME == CODE_METADATA_NAME
