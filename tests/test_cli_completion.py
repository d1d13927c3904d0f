"""Shell completion (issue 19): it installs, and the installed script completes commands,
options and choices, without importing every command to list their names."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from aeroexec.cli.commands import COMMANDS

ROOT = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent
BASH = shutil.which("bash")

pytestmark = pytest.mark.skipif(
    BASH is None or not (BIN / "aeroexec").exists(),
    reason="needs bash and the aeroexec console script next to this Python",
)


def in_bash(script: str, home: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "HOME": str(home), "PATH": f"{BIN}{os.pathsep}{os.environ['PATH']}"}
    return subprocess.run(
        [BASH, "--norc", "--noprofile", "-c", script],
        env=env,
        cwd=home,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A home where `aeroexec --install-completion` ran from bash (which it detects)."""
    home = tmp_path_factory.mktemp("home")
    # `; true`: bash forks for the command instead of exec'ing it, so it stays the parent.
    done = in_bash("aeroexec --install-completion; true", home)
    assert "bash completion installed" in done.stdout, done.stdout + done.stderr
    return home


def complete(home: Path, *words: str) -> list[str]:
    quoted = " ".join(f"'{w}'" for w in ("aeroexec", *words))
    done = in_bash(
        "source ~/.bash_completions/aeroexec.sh\n"
        f"COMP_WORDS=({quoted}); COMP_CWORD={len(words)}\n"
        '_aeroexec_completion aeroexec; printf "%s\\n" "${COMPREPLY[@]}"',
        home,
    )
    assert done.returncode == 0, done.stderr
    return done.stdout.split()


def test_install_completion_adds_a_script_the_shell_sources(installed: Path) -> None:
    script = installed / ".bash_completions" / "aeroexec.sh"
    assert "complete -o default -F _aeroexec_completion aeroexec" in script.read_text()
    assert f"source '{script}'" in (installed / ".bashrc").read_text()


def test_the_installed_script_completes_commands_options_and_choices(installed: Path) -> None:
    assert complete(installed, "") == list(COMMANDS)
    assert complete(installed, "v") == ["verify", "view"]
    assert complete(installed, "catalog", "") == ["show"]
    options = complete(installed, "run", "--")
    assert {"--output", "--catalog", "--world", "--quiet", "--color", "--help"} <= set(options)
    assert "--record" not in options  # a deprecated spelling is not offered
    assert complete(installed, "replay", "-f", "") == ["text", "json", "junit"]
    assert complete(installed, "verify", "--color", "a") == ["auto", "always"]


def test_show_completion_prints_the_script_for_the_shell() -> None:
    home = ROOT  # only read
    done = in_bash("aeroexec --show-completion; true", home)
    assert done.returncode == 0
    assert "_AEROEXEC_COMPLETE=complete_bash" in done.stdout


PROBE = """
import contextlib, io, json, sys
sys.argv = ["aeroexec"]
from aeroexec.cli import main
out = io.StringIO()
try:
    with contextlib.redirect_stdout(out):
        main()
except SystemExit:
    pass
print(json.dumps({"out": out.getvalue(), "modules": sorted(sys.modules)}))
"""


def test_completing_a_command_name_imports_no_command() -> None:
    env = {
        **os.environ,
        "_AEROEXEC_COMPLETE": "complete_bash",
        "COMP_WORDS": "aeroexec ",
        "COMP_CWORD": "1",
    }
    done = subprocess.run(
        [sys.executable, "-c", PROBE],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["out"].split() == list(COMMANDS)
    assert [
        m for m in result["modules"] if m.startswith("aeroexec.cli.") and m.endswith("_cmd")
    ] == []
