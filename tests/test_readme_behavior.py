"""README's "Writing a behavior" is the whole path, and it works as written: its
behavior and configuration, dropped into a temporary project, are found, verified, run
and replayed by the commands it lists."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.catalog import DEFAULT_CATALOG
from aeroexec.cli import app

README = Path(__file__).resolve().parent.parent / "README.md"


def section() -> str:
    text = README.read_text(encoding="utf-8")
    start = text.index("## Writing a behavior")
    return text[start : text.index("\n## ", start + 1)]


def test_the_section_fits_on_a_page() -> None:
    assert len(section().splitlines()) <= 66


def test_the_section_works_as_written(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    text = section()
    (python,) = re.findall(r"```python\n(.*?)```", text, re.S)
    (toml,) = re.findall(r"```toml\n(.*?)```", text, re.S)
    (shell,) = re.findall(r"```sh\n(.*?)```", text, re.S)
    module = python.splitlines()[0].removeprefix("# ").strip()
    package = tmp_path / module
    package.parent.mkdir(parents=True)
    (package.parent / "__init__.py").write_text("")
    package.write_text(python)
    (tmp_path / "pyproject.toml").write_text(toml)
    catalog = DEFAULT_CATALOG.read_text(encoding="utf-8").replace(
        "behavior_lists:",
        "  - behavior: SURVEY\n    timeout: 60\n    recurrent: no\n    arguments:\n"
        "      - argument: side\n        allowed_values: [1, 10]\n\nbehavior_lists:",
        1,
    )
    (tmp_path / "catalog.yaml").write_text(catalog)
    (tmp_path / "mission.py").write_text(
        "import executive_engine_api as api\n\ndef runMission():\n"
        "    api.executeBehavior('TAKE_OFF')\n"
        "    assert api.executeBehavior('SURVEY', side=3) == 'GOAL_ACHIEVED'\n"
        "    api.executeBehavior('LAND')\n"
    )
    monkeypatch.chdir(tmp_path)
    outputs = []
    for line in shell.splitlines():
        command = shlex.split(line.split("#")[0])
        if command[:2] == ["aeroexec", "fly"]:
            continue  # needs an autopilot: tests/test_plugins_acceptance.py flies it
        result = CliRunner().invoke(app, command[1:])
        assert result.exit_code == 0, (line, result.output)
        outputs.append(result.stdout)
    listed, verified, ran, replayed = outputs
    assert "SURVEY" in listed and "mybehaviors.survey:Survey" in listed
    assert verified.startswith("0 errors, 0 warnings")
    assert "SURVEY GOAL_ACHIEVED" in ran
    assert "no differences" in replayed and "code changed" not in replayed
