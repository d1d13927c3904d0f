"""`aeroexec catalog show`: the output itself, and bad input through the real CLI.

Bad input must give exactly one stderr line `file:line:col: error: ...` (or `file: error:
...` when there is no position), exit code 2 and never a traceback: checked in-process
with typer's CliRunner and, for the cases where the process matters (a YAML tag that
would run a shell command, the alias bomb, hash-seed independence), in a real
`python -m aeroexec` subprocess.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest
from rich.console import Console
from typer.testing import CliRunner

from aeroexec.catalog import DEFAULT_CATALOG, THESIS_CATALOG, Catalog, load_catalog, parse_catalog
from aeroexec.catalog.show import catalog_to_json, conflicts, preempts, render_plain, render_rich
from aeroexec.cli import app

runner = CliRunner()
ANSI = re.compile(r"\x1b\[[0-9;]*m")


def show(*args: str) -> tuple[int, str, str]:
    result = runner.invoke(app, ["catalog", "show", *args])
    # CliRunner swallows exceptions into result.exception: an escaped one is a failure
    # even though nothing was printed.
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(
        result.exception
    )
    return result.exit_code, result.stdout, result.stderr


def run_module(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "aeroexec", *args],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
        env={**os.environ, **(env or {})},
    )


def position(text: str, needle: str) -> str:
    index = text.index(needle)
    line = text.count("\n", 0, index) + 1
    return f"{line}:{index - (text.rfind(chr(10), 0, index) + 1) + 1}"


# -- bad input ----------------------------------------------------------------------------

GOOD = (
    "behavior_descriptors:\n"
    "  - behavior: GO\n"
    "    timeout: 30\n"
    "    recurrent: no\n"
    "capability_descriptors: []\n"
)
BOMB = "\n".join(
    ['a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]']
    + [
        f"{name}: &{name} [" + ",".join([f"*{prev}"] * 9) + "]"
        for prev, name in zip("abcdefgh", "bcdefghi", strict=True)
    ]
)
PYTHON_TAG = 'behavior_descriptors: !!python/object/apply:os.system ["echo hi"]\n'


@dataclass(frozen=True)
class Bad:
    content: bytes | None  # None: the path does not exist; b"<dir>": a directory
    expected: Callable[[str], str]  # path -> the exact stderr line


def _text(text: str) -> bytes:
    return text.encode("utf-8")


BAD: dict[str, Bad] = {
    "missing file": Bad(None, lambda p: f"{p}: error: no such file"),
    "directory": Bad(b"<dir>", lambda p: f"{p}: error: is a directory, not a catalog file"),
    "invalid yaml": Bad(
        _text("behavior_descriptors:\n  - behavior: GO\n    timeout: 30: 40\n"),
        # libyaml and PyYAML word it differently; both point at the second ':'.
        lambda p: f"{p}:3:16: error: invalid YAML: mapping values are not allowed",
    ),
    "not a mapping": Bad(
        _text("- TAKE_OFF\n- LAND\n"),
        lambda p: f"{p}:1:1: error: a catalog is a mapping with behavior_descriptors, got a list",
    ),
    "missing error tag": Bad(
        _text(GOOD.replace("capability_descriptors: []\n", "")),
        lambda p: (
            f"{p}:1:1: error: missing 'capability_descriptors' (an error tag: the catalog "
            "cannot load without it) [AX101]"
        ),
    ),
    "wrong type": Bad(
        _text(GOOD.replace("timeout: 30", "timeout: fast")),
        lambda p: (
            f"{p}:{position(GOOD.replace('timeout: 30', 'timeout: fast'), 'fast')}: error: "
            "GO: timeout must be a positive number of seconds, got str ('fast') [AX105]"
        ),
    ),
    "python tag": Bad(
        _text(PYTHON_TAG),
        lambda p: (
            f"{p}:1:23: error: YAML tag 'tag:yaml.org,2002:python/object/apply:os.system' "
            "is not allowed (aeroexec never executes tags)"
        ),
    ),
    "alias bomb": Bad(
        _text(BOMB),
        # The 4th alias of line 7 is where the expansion passes 2,500,000 nodes.
        lambda p: (
            f"{p}:7:17: error: document expands to too many nodes (alias bomb?); "
            "refusing to expand it"
        ),
    ),
    "recursive alias": Bad(
        _text("behavior_descriptors: &x [1, *x]\n"),
        lambda p: f"{p}:1:30: error: recursive alias: a node contains itself",
    ),
    "name with a newline": Bad(
        _text(GOOD.replace("behavior: GO", 'behavior: "G\\nO"').replace("30", "fast")),
        lambda p: (
            f"{p}:3:14: error: G\\nO: timeout must be a positive number of seconds, "
            "got str ('fast') [AX105]"
        ),
    ),
    "empty file": Bad(
        b"",
        lambda p: f"{p}:1:1: error: empty document: a catalog needs behavior_descriptors",
    ),
    "not utf-8": Bad(
        b"behavior_descriptors: []\nname: caf\xe9\n",
        lambda p: f"{p}:2:10: error: not UTF-8 text (byte 34)",
    ),
}


def make(tmp_path: Path, bad: Bad) -> Path:
    path = tmp_path / "catalog.yaml"
    if bad.content == b"<dir>":
        path.mkdir()
    elif bad.content is not None:
        path.write_bytes(bad.content)
    return path


def assert_one_error_line(stderr: str, expected: str) -> None:
    lines = stderr.splitlines()
    assert len(lines) == 1, stderr
    if "mapping values are not allowed" in expected:
        assert lines[0].startswith(expected)  # the wording's tail depends on the parser
    else:
        assert lines[0] == expected


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_input_cli(tmp_path: Path, case: str) -> None:
    path = make(tmp_path, BAD[case])
    start = time.perf_counter()
    code, stdout, stderr = show(str(path))
    elapsed = time.perf_counter() - start
    assert code == 2
    assert stdout == ""
    assert "Traceback" not in stdout + stderr
    assert_one_error_line(stderr, BAD[case].expected(str(path)))
    assert elapsed < 1.0, f"{case} took {elapsed:.2f} s"


@pytest.mark.parametrize("case", ["python tag", "alias bomb", "not utf-8", "missing file"])
def test_bad_input_subprocess(tmp_path: Path, case: str) -> None:
    path = make(tmp_path, BAD[case])
    result = run_module("catalog", "show", str(path))
    assert result.returncode == 2
    assert "Traceback" not in result.stdout + result.stderr
    assert result.stdout == ""  # `echo hi` did not run
    assert_one_error_line(result.stderr, BAD[case].expected(str(path)))


def test_python_tag_is_not_executed_by_the_cli(tmp_path: Path) -> None:
    marker = tmp_path / "pwned"
    path = tmp_path / "catalog.yaml"
    path.write_text(f'behavior_descriptors: !!python/object/apply:os.system ["touch {marker}"]\n')
    result = run_module("catalog", "show", str(path))
    assert result.returncode == 2
    assert not marker.exists()


def test_bad_format_option_is_a_usage_error() -> None:
    result = runner.invoke(app, ["catalog", "show", str(THESIS_CATALOG), "--format", "yaml"])
    assert result.exit_code == 2
    assert "yaml" in result.stderr and "Traceback" not in result.output


def test_missing_file_argument_is_a_usage_error() -> None:
    result = runner.invoke(app, ["catalog", "show"])
    assert result.exit_code == 2
    assert result.stderr == (
        "aeroexec catalog show: error: missing argument CATALOG "
        "(aeroexec catalog show -h for help)\n"
    )


# -- help ---------------------------------------------------------------------------------


def test_help_explains_with_examples() -> None:
    group = runner.invoke(app, ["catalog", "--help"])
    assert group.exit_code == 0
    assert "aeroexec catalog show catalog/aerostack-2017.yaml" in group.stdout
    assert "show" in group.stdout
    command = runner.invoke(app, ["catalog", "show", "--help"])
    assert command.exit_code == 0
    text = command.stdout
    assert "Examples:" in text
    # The example lines survive help re-wrapping intact (one per line).
    assert "\n    aeroexec catalog show catalog/aerostack-2017.yaml\n" in text
    assert "-f json" in text and "--format" in text
    assert "file:line:col" in text
    assert "`aeroexec verify CATALOG` is the check" in " ".join(text.split())


# -- text output --------------------------------------------------------------------------


def test_text_shows_every_behavior_with_its_timeout(thesis_catalog: Catalog) -> None:
    code, out, err = show(str(THESIS_CATALOG))
    assert (code, err) == (0, "")
    assert not ANSI.search(out)  # not a terminal: no colors
    lines = out.splitlines()
    text = THESIS_CATALOG.read_text(encoding="utf-8")
    for name, behavior in thesis_catalog.behaviors.items():
        timeout = "none" if behavior.timeout is None else f"{behavior.timeout:g} s"
        recurrent = "yes" if behavior.recurrent else "no"
        line = position(text, f"behavior: {name}\n").split(":")[0]
        assert f"  {name}  timeout {timeout}  recurrent {recurrent}  line {line}" in lines
    assert "  GO_TO_POINT  timeout 120 s  recurrent no  line 17" in lines
    assert "  PAY_ATTENTION  timeout none  recurrent yes  line 56" in lines


def test_text_details(thesis_catalog: Catalog) -> None:
    out = render_plain(thesis_catalog)
    block = out.split("\n  GO_TO_POINT  ")[1].split("\n  ROTATE  ")[0].splitlines()
    fields = [" ".join(line.split()) for line in block[1:]]
    assert fields == [
        "incompatible_lists motion_behaviors, rotation_behaviors",
        "preempts TAKE_OFF, LAND, FLIP, KEEP_HOVERING, FOLLOW_OBJECT_IMAGE, START_MOVING, "
        "START_HOVERING, GO_TO_POINT, VISUAL_SERVOING, ROTATE, LOOK_AT_POINT",
        "capabilities SETPOINT_BASED_FLIGHT_CONTROL, PATH_PLANNING",
        "argument COORDINATES: 3 numbers in [-100, 100]",
        "argument RELATIVE_COORDINATES: 3 numbers in [-100, 100]",
    ]
    squeezed = [" ".join(line.split()) for line in out.splitlines()]
    assert "argument DIRECTION: one of BACKWARD, FORWARD, UP, DOWN, LEFT, RIGHT" in squeezed
    assert "argument TEXT: text" in squeezed
    assert "behaviors ROTATE, LOOK_AT_POINT" in squeezed
    assert "processes trackerEye, open_tld_translator, droneIBVSController" in squeezed
    assert "conflicts SETPOINT_BASED_FLIGHT_CONTROL" in squeezed
    assert "SELF_LOCALIZATION_BY_ODOMETRY active_by_default yes line 133" in squeezed
    assert "default capabilities: SELF_LOCALIZATION_BY_ODOMETRY" in squeezed
    assert (
        "dialect thesis-2017: thesis 2017 Appendix A (recurrent, processes, active_by_default)"
        in squeezed
    )
    assert "summary 12 behaviors, 2 lists, 6 capabilities (1 active by default)" in squeezed


def test_text_ends_with_the_loader_diagnostics(thesis_catalog: Catalog) -> None:
    out = render_plain(thesis_catalog)
    path = str(THESIS_CATALOG)
    before, after = out.split("\nloader diagnostics (0 errors, 2 warnings, ")
    # Saying what the diagnostics are not: the verifier's rules.
    assert before.endswith(
        f"\n`aeroexec verify {path}` is the check: references, conflicts, start order, missions"
    )
    tail = after.splitlines()[1:]
    assert tail == [str(d) for d in sorted(thesis_catalog.diagnostics, key=lambda d: d.mark.line)]
    assert (
        f"{path}:137:5: warning AX102 capability SELF_LOCALIZATION_BY_VISUAL_MARKERS: "
        "no active_by_default; 'no' is applied"
    ) in tail
    pattern = re.compile(rf"^{re.escape(path)}:\d+:\d+: (error|warning|info) AX1\d\d \S")
    assert all(pattern.match(line) for line in tail)


def test_text_warnings_of_a_catalog_with_problems(tmp_path: Path) -> None:
    text = (
        "behavior_descriptors:\n"
        "  - behavior: GO\n"
        "    timeot: 30\n"
        "    recurrent: no\n"
        "  - behavior: GO\n"
        "    timeout: 5\n"
        "    recurrent: no\n"
        "capability_descriptors:\n"
        "  - capability: CAM\n"
        "    activate_by_default: yes\n"
        "    processes: [cam]\n"
    )
    path = tmp_path / "c.yaml"
    path.write_text(text)
    code, out, _ = show(str(path))
    assert code == 0
    assert (
        f"{path}:3:5: warning AX104 unknown tag 'timeot' in behavior GO (did you mean 'timeout'?)"
        in out
    )
    assert f"{path}:5:5: warning AX106 behavior GO is defined again (first at line 2)" in out
    assert f"{path}:10:5: warning AX104 'activate_by_default' is not a catalog tag" in out
    assert "  GO  timeout 5 s  recurrent no  line 5" in out.splitlines()
    assert "  CAM  active_by_default yes  line 9" in out.splitlines()


def test_text_is_identical_under_different_hash_seeds() -> None:
    # Sets inside the catalog indexes must never decide output order.
    outputs = {
        run_module("catalog", "show", str(DEFAULT_CATALOG), env={"PYTHONHASHSEED": seed}).stdout
        for seed in ("1", "2", "3")
    }
    assert len(outputs) == 1
    assert "GO_TO_POINT" in outputs.pop()


def test_stable_orders_match_the_indexes(thesis_catalog: Catalog) -> None:
    for name in thesis_catalog.behaviors:
        ordered = preempts(thesis_catalog, name)
        assert len(set(ordered)) == len(ordered)
        assert set(ordered) == thesis_catalog.preempted_by(name)
    for name in thesis_catalog.capabilities:
        assert set(conflicts(thesis_catalog, name)) == thesis_catalog.conflicts_of(name)
    # An undefined capability named in a conflict sorts after the defined ones.
    catalog = parse_catalog(
        "behavior_descriptors: []\ncapability_descriptors:\n"
        "  - {capability: B, processes: [p], active_by_default: no,"
        " incompatible_capabilities: [ZZ, A, C]}\n"
        "  - {capability: C, processes: [q], active_by_default: no}\n"
        "  - {capability: A, processes: [r], active_by_default: no}\n"
    )
    assert conflicts(catalog, "B") == ("C", "A", "ZZ")


# -- JSON output --------------------------------------------------------------------------


def test_json_output(thesis_catalog: Catalog) -> None:
    code, out, err = show(str(THESIS_CATALOG), "--format", "json")
    assert (code, err) == (0, "")
    data = json.loads(out)
    assert data["format"] == "aeroexec.catalog.show/1"
    assert data["file"] == str(THESIS_CATALOG)
    assert data["dialect"] == "thesis-2017"
    assert data["counts"] == {"behaviors": 12, "lists": 2, "capabilities": 6}
    assert [b["name"] for b in data["behaviors"]] == list(thesis_catalog.behaviors)
    assert [c["name"] for c in data["capabilities"]] == list(thesis_catalog.capabilities)
    assert data["default_capabilities"] == ["SELF_LOCALIZATION_BY_ODOMETRY"]
    by_name = {b["name"]: b for b in data["behaviors"]}
    go = by_name["GO_TO_POINT"]
    assert (go["timeout"], go["recurrent"], go["line"], go["column"]) == (120, False, 17, 5)
    assert go["capabilities"] == ["SETPOINT_BASED_FLIGHT_CONTROL", "PATH_PLANNING"]
    assert go["preempts"][:2] == ["TAKE_OFF", "LAND"] and len(go["preempts"]) == 11
    assert go["arguments"][0] == {
        "name": "COORDINATES",
        "kind": "range",
        "minimum": -100,
        "maximum": 100,
        "dimensions": 3,
        "symbols": [],
        "allowed": "3 numbers in [-100, 100]",
        "line": 23,
        "column": 9,
    }
    direction = by_name["START_MOVING"]["arguments"][1]
    assert (direction["kind"], direction["symbols"]) == (
        "symbols",
        ["BACKWARD", "FORWARD", "UP", "DOWN", "LEFT", "RIGHT"],
    )
    assert by_name["BROADCAST_MESSAGE"]["arguments"][0]["kind"] == "text"
    assert by_name["PAY_ATTENTION"]["timeout"] is None
    assert by_name["PAY_ATTENTION"]["recurrent"] is True
    sbfc = data["capabilities"][0]
    assert sbfc["conflicts"] == ["VISUAL_SERVOING"]
    assert sbfc["used_by"][0] == "GO_TO_POINT"
    assert data["lists"][1] == {
        "name": "rotation_behaviors",
        "line": 115,
        "column": 5,
        "behaviors": ["ROTATE", "LOOK_AT_POINT"],
        "named_by": [b for b, d in thesis_catalog.behaviors.items() if d.incompatible_lists],
    }


def test_json_diagnostics_point_at_the_right_lines(thesis_catalog: Catalog) -> None:
    data = catalog_to_json(thesis_catalog)
    lines = THESIS_CATALOG.read_text(encoding="utf-8").splitlines()
    diagnostics = data["diagnostics"]
    assert len(diagnostics) == len(thesis_catalog.diagnostics)
    warnings = [d for d in diagnostics if d["severity"] == "warning"]
    assert [(d["line"], d["column"], d["code"]) for d in warnings] == [
        (137, 5, "AX102"),
        (143, 5, "AX102"),
    ]
    assert set(diagnostics[0]) == {
        "file",
        "line",
        "column",
        "severity",
        "code",
        "message",
        "subjects",
    }
    for d in diagnostics:
        assert d["file"] == str(THESIS_CATALOG)
        if d["subjects"]:  # the line the mark names is the subject's definition
            assert d["subjects"][0] in lines[d["line"] - 1], d


def test_json_has_no_nan_or_infinity(tmp_path: Path) -> None:
    path = tmp_path / "c.yaml"
    path.write_text(
        "behavior_descriptors:\n"
        "  - behavior: B\n"
        "    timeout: 5\n"
        "    recurrent: no\n"
        "    arguments:\n"
        "      - argument: X\n"
        "        allowed_values: [-.inf, .inf]\n"
        "capability_descriptors: []\n"
    )
    code, out, _ = show(str(path), "--format", "json")
    assert code == 0
    (b,) = json.loads(out)["behaviors"]
    # Unbounded is null, as RFC 8259 JSON has no Infinity (an infinite timeout is
    # refused by the loader: the executive cannot arm it).
    assert (b["timeout"], b["arguments"][0]["minimum"], b["arguments"][0]["maximum"]) == (
        5,
        None,
        None,
    )
    assert "Infinity" not in out and "NaN" not in out


# -- the terminal view --------------------------------------------------------------------


def _terminal(catalog: Catalog, width: int) -> tuple[str, str]:
    console = Console(record=True, force_terminal=True, width=width, color_system="standard")
    render_rich(catalog, console)
    raw = console.export_text(styles=True)
    return raw, ANSI.sub("", raw)


def test_the_terminal_view(thesis_catalog: Catalog) -> None:
    raw, plain = _terminal(thesis_catalog, 120)
    for title in ("Behaviors (12)", "Lists (2)", "Capabilities (6)", "Loader diagnostics"):
        assert title in plain
    lines = plain.splitlines()
    assert "  GO_TO_POINT  timeout 120 s" in lines
    assert "  PAY_ATTENTION  no timeout, recurrent" in lines
    block = plain.split("\n  GO_TO_POINT  timeout 120 s\n")[1].split("\n  ROTATE ")[0]
    assert [" ".join(line.split()) for line in block.splitlines()] == [
        "incompatible motion_behaviors, rotation_behaviors (preempts 11)",
        "capabilities SETPOINT_BASED_FLIGHT_CONTROL, PATH_PLANNING",
        "COORDINATES 3 numbers in [-100, 100]",
        "RELATIVE_COORDINATES 3 numbers in [-100, 100]",
    ]
    assert "  SELF_LOCALIZATION_BY_ODOMETRY  active by default" in lines
    assert "\x1b[33mwarning" in raw  # warnings in yellow
    # Warnings are listed, infos counted; and what the loader's checks are not.
    infos = sum(d.severity.value == "info" for d in thesis_catalog.diagnostics)
    assert f"{infos} infos not listed here (--color never or -f json lists them)" in lines
    assert " ".join(plain.split()).endswith(
        f"`aeroexec verify {THESIS_CATALOG}` is the check: references, conflicts, start order, "
        "missions"
    )


@pytest.mark.parametrize("catalog_file", [DEFAULT_CATALOG, THESIS_CATALOG])
def test_the_terminal_view_fits_80_columns_without_splitting_a_name(catalog_file: Path) -> None:
    catalog = load_catalog(catalog_file)
    _, plain = _terminal(catalog, 80)
    lines = plain.splitlines()
    assert max(len(line) for line in lines) <= 80
    assert len(lines) < 100  # the table layout took 262 lines for the default catalog
    words = set(re.findall(r"[A-Za-z0-9_]+", plain))
    names = [*catalog.behaviors, *catalog.lists, *catalog.capabilities]
    names += [p for c in catalog.capabilities.values() for p in c.processes]
    for name in names:
        assert name in words, f"{name} is split or missing"


def test_rich_prints_names_literally() -> None:
    catalog = parse_catalog(
        "behavior_descriptors:\n  - behavior: '[bold]X[/bold]'\n    timeout: 1\n"
        "    recurrent: no\ncapability_descriptors: []\n"
    )
    console = Console(record=True, force_terminal=True, width=200)
    render_rich(catalog, console)
    assert "[bold]X[/bold]" in console.export_text()


@pytest.mark.skipif(sys.platform == "win32", reason="needs a pseudo-terminal")
def test_terminal_gets_tables_and_a_pipe_gets_plain_text() -> None:
    import pty

    leader, follower = pty.openpty()
    process = subprocess.Popen(
        [sys.executable, "-m", "aeroexec", "catalog", "show", str(THESIS_CATALOG)],
        stdout=follower,
        stderr=subprocess.PIPE,
        env={**os.environ, "COLUMNS": "200", "TERM": "xterm"},
    )
    os.close(follower)
    chunks = []
    while True:
        try:
            chunk = os.read(leader, 65536)
        except OSError:  # EIO: the child closed the terminal
            break
        if not chunk:
            break
        chunks.append(chunk)
    assert process.wait(timeout=60) == 0
    os.close(leader)
    on_terminal = ANSI.sub("", b"".join(chunks).decode("utf-8", "replace"))
    assert "\n  GO_TO_POINT  timeout 120 s" in on_terminal.replace("\r\n", "\n")
    piped = run_module("catalog", "show", str(THESIS_CATALOG)).stdout
    assert "\x1b[" not in piped and piped.startswith(f"catalog {THESIS_CATALOG}\n")
    # --color decides it either way: always styles a pipe, never keeps a terminal plain.
    styled = run_module("catalog", "show", str(THESIS_CATALOG), "--color", "always").stdout
    assert "\x1b[" in styled and "\n  GO_TO_POINT  timeout 120 s" in ANSI.sub("", styled)
    no_color = run_module("catalog", "show", str(THESIS_CATALOG), env={"NO_COLOR": "1"}).stdout
    assert no_color == piped


def test_show_uses_the_strict_loader(tmp_path: Path) -> None:
    # read_catalog would return a catalog with an AX101 error; show must refuse it.
    path = tmp_path / "c.yaml"
    path.write_text("behavior_descriptors: []\n")
    code, out, err = show(str(path))
    assert code == 2 and out == ""
    assert err.startswith(f"{path}:1:1: error: missing 'capability_descriptors'")
    assert load_catalog(DEFAULT_CATALOG)  # the shipped default shows cleanly
    assert show(str(DEFAULT_CATALOG))[0] == 0
