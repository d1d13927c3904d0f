"""The project configuration: found upward like ruff's and pytest's, relative paths from
the file, one line (file:line) and exit 2 for a bad file."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.config import NO_CONFIG, find_config, load_config
from aeroexec.errors import ConfigError


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def test_nearest_pyproject_with_the_table_wins_and_paths_resolve_from_it(tmp_path: Path) -> None:
    write(tmp_path / "pyproject.toml", '[tool.aeroexec]\ncatalog = "outer.yaml"\n')
    write(tmp_path / "proj" / "pyproject.toml", '[tool.aeroexec]\ncatalog = "cat/inner.yaml"\n')
    deep = tmp_path / "proj" / "src" / "deeper"
    deep.mkdir(parents=True)
    config = load_config(deep)
    assert config.path == (tmp_path / "proj" / "pyproject.toml").resolve()
    assert config.catalog == (tmp_path / "proj" / "cat" / "inner.yaml").resolve()


def test_a_pyproject_without_the_table_is_passed_over(tmp_path: Path) -> None:
    write(tmp_path / "pyproject.toml", '[tool.aeroexec]\nseed = 7\nbehaviors = ["pkg"]\n')
    write(tmp_path / "sub" / "pyproject.toml", '[project]\nname = "x"\n[tool.ruff]\n')
    config = load_config(tmp_path / "sub")
    assert config.path == (tmp_path / "pyproject.toml").resolve()
    assert config.seed == 7
    assert config.behaviors == ("pkg",)


def test_aeroexec_toml_is_read_at_top_level_and_before_pyproject(tmp_path: Path) -> None:
    write(tmp_path / "pyproject.toml", "[tool.aeroexec]\nseed = 1\n")
    write(tmp_path / "aeroexec.toml", 'seed = 2\nworld = "/abs/world.yaml"\nbehaviors = []\n')
    config = load_config(tmp_path)
    assert config.path is not None and config.path.name == "aeroexec.toml"
    assert config.seed == 2
    assert config.world == Path("/abs/world.yaml")
    assert config.behaviors == ()  # an empty list is a statement, not "absent"


def test_no_configuration_means_nothing_is_pinned(tmp_path: Path) -> None:
    write(tmp_path / "pyproject.toml", '[project]\nname = "x"\n')
    config = load_config(tmp_path)
    if find_config(tmp_path) is None:  # nothing above the temporary directory either
        assert config == NO_CONFIG
    assert config.path != (tmp_path / "pyproject.toml").resolve()
    assert NO_CONFIG.behaviors is None and NO_CONFIG.catalog is None


@pytest.mark.parametrize(
    ("text", "line", "message"),
    [
        (
            '[project]\nname = "x"\n\n[tool.aeroexec]\nbehavior = ["x"]\n',
            5,
            "unknown key 'behavior'",
        ),
        ('[tool.aeroexec]\ncatalog = "c.yaml"\nseed = "seven"\n', 3, "'seed' must be an integer"),
        ("[tool.aeroexec]\nbehaviors = [1, 2]\n", 2, "'behaviors' must be a list"),
        ("[tool.aeroexec]\nseed = true\n", 2, "'seed' must be an integer"),
        ("[tool.aeroexec\nseed = 1\n", 1, "invalid TOML"),
        ("[tool]\naeroexec = 3\n", 0, "[tool.aeroexec] must be a table"),
    ],
)
def test_a_bad_file_is_one_error_at_its_line(
    tmp_path: Path, text: str, line: int, message: str
) -> None:
    path = write(tmp_path / "pyproject.toml", text)
    with pytest.raises(ConfigError) as caught:
        load_config(tmp_path)
    error = caught.value
    assert error.mark is not None
    assert Path(error.mark.file).resolve() == path.resolve()
    assert error.mark.line == line
    assert message in error.message


def test_the_cli_reports_a_bad_configuration_in_one_line_with_exit_2(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    write(tmp_path / "aeroexec.toml", 'seed = 1\ncatalgo = "c.yaml"\n')
    monkeypatch.chdir(tmp_path)
    for args in (["run", "m.py"], ["behaviors"], ["verify"], ["replay", "r.mcap"]):
        result = CliRunner().invoke(app, args)
        assert result.exit_code == 2, (args, result.output)
        lines = result.stderr.strip().splitlines()
        assert lines == [
            "aeroexec.toml:2:1: error: unknown key 'catalgo' (did you mean 'catalog'?)"
        ]


def test_command_line_wins_over_the_file_which_wins_over_defaults(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """`run` takes the project's seed and world; an explicit --seed wins."""
    world = write(
        tmp_path / "worlds" / "far.yaml",
        "name: far\nvehicle:\n  start: [5, 0, 0]\n",
    )
    write(tmp_path / "pyproject.toml", '[tool.aeroexec]\nworld = "worlds/far.yaml"\nseed = 3\n')
    mission = write(
        tmp_path / "m.py",
        "import executive_engine_api as api\n\ndef runMission():\n"
        "    api.executeBehavior('WAIT', duration=1)\n",
    )
    monkeypatch.chdir(tmp_path)
    rec = tmp_path / "a.mcap"
    result = CliRunner().invoke(app, ["run", str(mission), "-o", str(rec), "-q"])
    assert result.exit_code == 0, result.output
    assert "vehicle landed at (5.00, 0.00, 0.00)" in result.output  # the project's world
    from aeroexec.recording import open_recording

    metadata = open_recording(rec).metadata["aeroexec"]
    assert metadata["seed"] == "3" and metadata["world"] == world.name
    result = CliRunner().invoke(app, ["run", str(mission), "-o", str(rec), "-q", "--seed", "9"])
    assert result.exit_code == 0, result.output
    assert open_recording(rec).metadata["aeroexec"]["seed"] == "9"


def test_aeroexec_toml_with_a_tool_table_says_where_keys_go(tmp_path: Path) -> None:
    write(tmp_path / "aeroexec.toml", "[tool.aeroexec]\nseed = 1\n")
    with pytest.raises(ConfigError, match=r"keys are at the top level, without a \[tool"):
        load_config(tmp_path)
