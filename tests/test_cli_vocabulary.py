"""One command line, from the first command to the last (issue 19).

Walks every command and subcommand, loaded through the lazy command table
(aeroexec/cli/commands.py) as `aeroexec` itself loads them, and every parameter, and
holds each to the vocabulary docs/cli.md writes down: the tables of that page are parsed
here, so the page and the commands cannot drift apart. The README's and the docs'
command lines are held to the same options.
"""

from __future__ import annotations

import re
import sys
from collections import defaultdict
from collections.abc import Iterator
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import Any

import pytest
import typer.main
from typer.testing import CliRunner

import aeroexec
from aeroexec.cli import app
from aeroexec.cli.command import Command, Group
from aeroexec.cli.commands import COMMANDS

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "cli.md"
runner = CliRunner()


# -- the vocabulary, as docs/cli.md writes it ---------------------------------------------
def _section(title: str) -> str:
    text = DOC.read_text(encoding="utf-8")
    start = text.index(f"\n## {title}\n")
    end = text.find("\n## ", start + 1)
    return text[start : end if end != -1 else len(text)]


def _table_rows(section: str) -> list[list[str]]:
    rows = []
    for line in section.splitlines():
        if line.startswith("| ") and not line.startswith("| ---"):
            cells = re.split(r"(?<!\\)\|", line.strip().strip("|"))
            rows.append([cell.strip().replace("\\|", "|") for cell in cells])
    return rows[1:]  # less the header


def _ticked(cell: str) -> list[str]:
    return re.findall(r"`([^`]+)`", cell)


@dataclass(frozen=True)
class Spelling:
    long: str
    short: str | None
    metavar: str | None  # "[...]": a choice list


def _shared() -> dict[str, Spelling]:
    found = {}
    for row in _table_rows(_section("Options with one meaning everywhere")):
        short, long, metavar = None, None, None
        for token in _ticked(row[0]):
            name, _, value = token.partition(" ")
            if name.startswith("--"):
                long, metavar = name, value or None
            else:
                short = name
        assert long is not None, row
        if metavar is not None and metavar.startswith("["):
            metavar = "[...]" if "..." in metavar else metavar
        found[long] = Spelling(long, short, metavar)
    return found


SHARED = _shared()
SHORT_FLAGS = set(
    re.search(r"Short flags are these and no others: `([^`]+)`", DOC.read_text())[1].split()  # type: ignore[index]
)
METAVAR_WORDS = {
    word for word in _ticked(_section("Metavars")) if re.fullmatch(r"[A-Z][A-Z0-9_/=@]*", word)
}
COLOR_COMMANDS = {
    f"aeroexec {name}"
    for name in _ticked(
        next(
            row
            for row in _table_rows(_section("Options with one meaning everywhere"))
            if row[0].startswith("`--color")
        )[1].split("On every command that styles")[1]
    )
}


def _deprecated() -> dict[str, dict[str, str]]:
    """{command path: {old option name: new long name}}"""
    found: dict[str, dict[str, str]] = defaultdict(dict)
    for old, new, commands in _table_rows(_section("Deprecated spellings")):
        new_long = next(name for name in _ticked(new) if name.startswith("--"))
        for command in _ticked(commands):
            for name in _ticked(old):
                found[f"aeroexec {command}"][name] = new_long
    return found


DEPRECATED = _deprecated()


# -- every command, as `aeroexec` loads it ------------------------------------------------
def _walk() -> Iterator[tuple[str, Any]]:
    root = typer.main.get_command(app)
    yield "aeroexec", root
    for name in COMMANDS:
        command = root.commands[name]  # type: ignore[attr-defined]
        yield f"aeroexec {name}", command
        for sub, subcommand in getattr(command, "commands", {}).items():
            yield f"aeroexec {name} {sub}", subcommand


WALKED = dict(_walk())
LEAVES = {path: c for path, c in WALKED.items() if not hasattr(c, "commands")}
GROUPS = {path: c for path, c in WALKED.items() if hasattr(c, "commands")}


def params(command: Any, *, hidden: bool = False) -> list[Any]:
    return [p for p in command.params if hidden or not getattr(p, "hidden", False)]


def options(command: Any, *, hidden: bool = False) -> list[Any]:
    return [p for p in params(command, hidden=hidden) if p.param_type_name == "option"]


def long_name(param: Any) -> str:
    return max(param.opts, key=len)


def short_names(param: Any) -> list[str]:
    return [name for name in param.opts if not name.startswith("--")]


def is_flag(param: Any) -> bool:
    return bool(getattr(param, "is_flag", False))


def choice_values(param: Any) -> list[str] | None:
    annotation = param.type_descriptor.annotation
    kind = next((a for a in getattr(annotation, "__args__", ()) if isinstance(a, type)), None)
    kind = annotation if isinstance(annotation, type) else kind
    if isinstance(kind, type) and issubclass(kind, Enum):
        return [str(member.value) for member in kind]
    return None


def render_help(path: str) -> str:
    result = runner.invoke(app, [*path.split()[1:], "--help"], terminal_width=80)
    assert result.exit_code == 0, result.output
    return result.stdout


HELP = {path: render_help(path) for path in WALKED}


# -- the rules ----------------------------------------------------------------------------
def test_every_command_of_the_table_loads_as_an_aeroexec_command() -> None:
    assert [p.split()[1] for p in WALKED if p.count(" ") == 1] == list(COMMANDS)
    for path, command in LEAVES.items():
        assert isinstance(command, Command), path
    for path, group in GROUPS.items():
        assert isinstance(group, Group), path
        assert group.commands, path


@pytest.mark.parametrize("path", sorted(WALKED))
def test_help_explains_with_an_example_and_every_parameter(path: str) -> None:
    command = WALKED[path]
    assert (command.help or "").strip(), path
    if path != "aeroexec":
        assert re.search(r"^\s*Examples?\b[^\n]*:$", command.help, re.MULTILINE), (
            f"{path}: help has no example"
        )
    for param in params(command):
        if path == "aeroexec" and param.name in ("install_completion", "show_completion"):
            continue  # typer's own wording
        text = (getattr(param, "help", None) or "").strip()
        assert text, f"{path} {param.name}: no help"
        assert text.endswith((".", ")")), f"{path} {param.name}: help is not a sentence"


@pytest.mark.parametrize("path", sorted(WALKED))
def test_names_are_lowercase_words_and_short_flags_are_the_vocabulary(path: str) -> None:
    for param in options(WALKED[path], hidden=True):
        longs = [n for n in [*param.opts, *param.secondary_opts] if n.startswith("--")]
        assert longs, f"{path}: {param.opts} has no long name"
        for name in longs:
            assert re.fullmatch(r"--[a-z0-9]+(-[a-z0-9]+)*", name), f"{path}: {name}"
        for short in short_names(param):
            if getattr(param, "hidden", False):
                continue  # a deprecated spelling (checked below)
            assert short in SHORT_FLAGS, f"{path}: {short} is not one of {sorted(SHORT_FLAGS)}"


def test_a_short_flag_means_one_option_everywhere() -> None:
    meaning: dict[str, set[str]] = defaultdict(set)
    for command in WALKED.values():
        for param in options(command):
            for short in short_names(param):
                meaning[short].add(long_name(param))
    meaning["-h"].add("--help")
    assert {short: longs for short, longs in meaning.items() if len(longs) > 1} == {}
    for short, longs in meaning.items():
        (long,) = longs
        if long in SHARED:
            assert SHARED[long].short == short, f"{short} {long}: docs/cli.md disagrees"


@pytest.mark.parametrize("path", sorted(WALKED))
def test_metavars_name_what_a_value_is(path: str) -> None:
    command = WALKED[path]
    for param in params(command, hidden=True):
        if param.param_type_name == "option" and is_flag(param):
            assert param.metavar is None, f"{path} {param.name}: a flag takes no value"
            continue
        metavar = param.metavar
        assert metavar, f"{path} {param.name}: no metavar"
        values = choice_values(param)
        if metavar.startswith("["):
            listed = metavar.strip("[]").split("|")
            if values is not None:
                assert listed == values, f"{path} {metavar}: accepts {values}"
            continue
        assert values is None, f"{path} {param.name}: a choice must list its values"
        word = metavar.removesuffix("...")
        assert word in METAVAR_WORDS, f"{path}: {metavar} is not a metavar of docs/cli.md"
        repeated = param.param_type_name == "argument" and param.nargs == -1
        assert metavar.endswith("...") == repeated, f"{path}: {metavar}"


@pytest.mark.parametrize("path", sorted(LEAVES))
def test_repeatable_options_say_so(path: str) -> None:
    for param in options(LEAVES[path]):
        if getattr(param, "multiple", False):
            assert "repeatable" in (param.help or ""), f"{path} {long_name(param)}"


def test_shared_options_are_spelled_as_docs_cli_md_says() -> None:
    users: dict[str, set[str]] = defaultdict(set)
    for path, command in LEAVES.items():
        for param in options(command):
            long = long_name(param)
            users[long].add(path)
            spelling = SHARED.get(long)
            if spelling is None:
                continue
            shorts = short_names(param)
            assert shorts == ([spelling.short] if spelling.short else []), f"{path} {long}"
            if spelling.metavar == "[...]":
                assert (param.metavar or "").startswith("["), f"{path} {long}"
            else:
                assert param.metavar == spelling.metavar, f"{path} {long}"
    shared_but_undocumented = {
        long: sorted(paths) for long, paths in users.items() if len(paths) > 1
    }
    for long in SHARED:
        shared_but_undocumented.pop(long, None)
    assert shared_but_undocumented == {}, "options of several commands belong in docs/cli.md"
    assert set(SHARED) - {"--help"} <= set(users), "docs/cli.md names an option no one has"


@pytest.mark.parametrize("path", sorted(LEAVES))
def test_formats_are_dash_f_and_text_first(path: str) -> None:
    for param in options(LEAVES[path]):
        values = choice_values(param) or []
        if long_name(param) == "--format":
            assert short_names(param) == ["-f"]
            assert values[0] == "text" and param.default.value == "text", path
        else:
            assert "json" not in values, f"{path} {long_name(param)}: formats are -f/--format"


def test_color_is_on_every_command_that_styles_and_no_other() -> None:
    having = set()
    for path, command in LEAVES.items():
        for param in options(command):
            if long_name(param) == "--color":
                having.add(path)
                assert choice_values(param) == ["auto", "always", "never"]
                assert param.default.value == "auto"
    assert having == COLOR_COMMANDS


@pytest.mark.parametrize("path", sorted(WALKED))
def test_hidden_parameters_are_documented_deprecated_spellings(path: str) -> None:
    command = WALKED[path]
    visible = {long_name(p) for p in options(command)}
    hidden = {n for p in options(command, hidden=True) if p.hidden for n in p.opts}
    if path == "aeroexec":
        return
    assert hidden == set(DEPRECATED.get(path, {})), path
    for old, new in DEPRECATED.get(path, {}).items():
        assert new in visible, f"{path}: {old} stands for {new}, which it lacks"


@pytest.mark.parametrize("path", sorted(WALKED))
def test_help_fits_80_columns_and_names_no_types_or_install_paths(path: str) -> None:
    text = HELP[path]
    for line in text.splitlines():
        assert len(line) <= 80, f"{path}: {line!r}"
    for stray in ("list[", "[[", "OUT.mcap"):
        assert stray not in text, f"{path}: {stray!r} in its help"
    listing = text.splitlines()[0] + text[text.find("\nArguments:\n") :]
    listing += text[text.find("\nOptions:\n") :]
    assert not re.search(r"<[a-z][a-z\[\]|]*>", listing), f"{path}: a type (<path>) in its help"
    install = Path(aeroexec.__file__).resolve().parent
    for place in {str(install), str(install.parent), sys.prefix, str(Path.home())}:
        assert place not in text, f"{path}: shows a path of the installation ({place})"


@pytest.mark.parametrize("path", sorted(WALKED))
def test_usage_line_names_arguments_by_their_metavars(path: str) -> None:
    command = WALKED[path]
    usage = HELP[path].splitlines()[0]
    pieces = ["[OPTIONS]"]
    for param in params(command):
        if param.param_type_name == "argument":
            pieces.append(param.metavar if param.required else f"[{param.metavar}]")
    if path in GROUPS:
        pieces.append("COMMAND [ARGS]...")
    assert usage == f"Usage: {path} {' '.join(pieces)}"


@pytest.mark.parametrize("path", sorted(WALKED))
def test_dash_h_is_help(path: str) -> None:
    result = runner.invoke(app, [*path.split()[1:], "-h"], terminal_width=80)
    assert result.exit_code == 0
    assert result.stdout == HELP[path]


@pytest.mark.parametrize("path", sorted(GROUPS))
def test_a_bare_group_prints_its_help_and_exits_0(path: str) -> None:
    result = runner.invoke(app, path.split()[1:], terminal_width=80)
    assert (result.exit_code, result.stderr) == (0, "")
    assert result.stdout == HELP[path]


def _one_error_line(args: list[str], path: str) -> str:
    result = runner.invoke(app, args, terminal_width=80)
    assert result.exit_code == 2, (args, result.output)
    assert result.stdout == "", args
    lines = result.stderr.splitlines()
    assert len(lines) == 1, (args, result.stderr)
    assert lines[0].startswith(f"{path}: error: "), lines[0]
    assert lines[0].endswith(f"({path} -h for help)"), lines[0]
    return lines[0]


def _bad_values(param: Any) -> list[str]:
    annotation = param.type_descriptor.annotation
    kinds = {a for a in getattr(annotation, "__args__", ()) if isinstance(a, type)}
    kinds.add(annotation) if isinstance(annotation, type) else None
    if choice_values(param) is not None:
        return ["no-such-choice"]
    if kinds & {int, float}:
        return ["not-a-number"]
    return []


@pytest.mark.parametrize("path", sorted(WALKED))
def test_a_wrong_command_line_is_one_line_and_exit_2(path: str) -> None:
    words = path.split()[1:]
    line = _one_error_line([*words, "--no-such-option"], path)
    assert "no such option --no-such-option" in line
    command = WALKED[path]
    required = [p for p in params(command) if p.param_type_name == "argument" and p.required]
    if required:
        line = _one_error_line(words, path)
        assert f"missing argument {required[0].metavar}" in line
    # Every value that is checked while parsing: a choice, a number.
    arguments = ["x"] * len(required)
    required_options = [
        token for p in options(command) if p.required for token in (long_name(p), "x")
    ]
    for param in options(command):
        if not is_flag(param):  # given last, without its value
            line = _one_error_line([*words, long_name(param)], path)
            assert f"option '{long_name(param)}' requires an argument" in line
        for bad in _bad_values(param):
            args = [*words, *arguments, *required_options, long_name(param), bad]
            line = _one_error_line(args, path)
            assert f"invalid value for {long_name(param)}: '{bad}'" in line


def test_a_removed_short_flag_says_what_to_use() -> None:
    line = _one_error_line(
        ["import", "flight.bag", "-o", "x.mcap", "-m", "t.yaml"], "aeroexec import"
    )
    assert "no such option -m; use --mapping" in line


# -- what people read uses the same words -------------------------------------------------
def _command_lines(text: str) -> Iterator[tuple[str, list[str]]]:
    """(command path, its tokens) for every `aeroexec CMD ...` in `text`."""
    for line in text.splitlines():
        for segment in re.split(r"&&|\|\||(?<!\\)\||;|\s#\s|`", line):
            tokens = segment.replace("\\|", "|").split()
            for i, token in enumerate(tokens):
                if token.rsplit("/", 1)[-1] != "aeroexec" or i + 1 >= len(tokens):
                    continue
                name = tokens[i + 1]
                if name not in COMMANDS:
                    continue
                path, rest = f"aeroexec {name}", tokens[i + 2 :]
                if rest and f"{path} {rest[0]}" in WALKED:
                    path, rest = f"{path} {rest[0]}", rest[1:]
                yield path, rest
                break


def _documents() -> Iterator[tuple[str, str]]:
    for file in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        text = file.read_text(encoding="utf-8")
        if file == DOC:
            text = text.replace(_section("Deprecated spellings"), "")
        yield str(file.relative_to(ROOT)), text
    for path in WALKED:
        yield f"`{path} --help`", HELP[path]


DOCUMENTS = dict(_documents())


@pytest.mark.parametrize("where", sorted(DOCUMENTS))
def test_every_command_line_people_read_uses_options_that_exist(where: str) -> None:
    seen = 0
    for path, tokens in _command_lines(DOCUMENTS[where]):
        command = WALKED[path]
        known = {"--help", "-h"} | {
            n for p in options(command) for n in [*p.opts, *p.secondary_opts]
        }
        for token in tokens:
            name = token.strip("[](),.:'\"").split("=")[0]
            if re.fullmatch(r"--?[a-z][a-z0-9-]*", name):
                assert name in known, f"{where}: `{path} ... {name}`: no such option"
        seen += 1
    if where in ("README.md", "docs/cli.md") or where.startswith("`aeroexec "):
        assert seen or where == "`aeroexec --help`" or where.endswith(" report --help`"), where
