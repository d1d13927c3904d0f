"""Files that are not regular files, or far too large, given where aeroexec reads input.

`/dev/zero` as a catalog used to grow a string to the size of memory; a FIFO as a
recording blocked forever in `open()`. Every reader goes through `aeroexec.inputs`, so
each of these is one line naming the file and exit code 2, at once.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.catalog.paths import DEFAULT_CATALOG
from aeroexec.cli import app
from aeroexec.errors import CatalogError, MissionError
from aeroexec.inputs import TEXT_LIMIT, read_bytes, read_text, regular_file

REPO = Path(__file__).resolve().parents[1]
MISSION = REPO / "missions" / "appendix_c.py"
BAG = REPO / "tests" / "fixtures" / "bags" / "ros1_turtlesim_example_lz4.bag"


@pytest.fixture(params=["/dev/zero", "/dev/urandom", "fifo"])
def hostile(request: pytest.FixtureRequest, tmp_path: Path) -> tuple[str, str]:
    """(path, what the error says it is)."""
    if request.param == "fifo":
        fifo = tmp_path / "pipe"
        os.mkfifo(fifo)  # nobody ever writes to it: opening it to read would block
        return str(fifo), "is a FIFO (named pipe)"
    if not Path(request.param).exists():
        pytest.skip(f"{request.param} does not exist here")
    return request.param, "is a character device"


COMMANDS = {
    "run mission": lambda f, out: ["run", f],
    "run catalog": lambda f, out: ["run", str(MISSION), "-c", f, "-q"],
    "run world": lambda f, out: ["run", str(MISSION), "--world", f, "-q"],
    "info recording": lambda f, out: ["info", f],
    "recover recording": lambda f, out: ["recover", f, "-o", out],
    "replay recording": lambda f, out: ["replay", f],
    "replay catalog": lambda f, out: ["replay", str(MISSION), "-c", f],
    "diff recording": lambda f, out: ["diff", f, f],
    "view recording": lambda f, out: ["view", f, "--output", out],
    "import bag": lambda f, out: ["import", f, "-o", out],
    "import mapping": lambda f, out: ["import", str(BAG), "--mapping", f, "-o", out],
    "verify catalog": lambda f, out: ["verify", f],
    "verify mission": lambda f, out: ["verify", str(DEFAULT_CATALOG), "--mission", f],
}


@pytest.mark.parametrize("command", list(COMMANDS))
def test_non_regular_inputs_are_refused_in_one_line(
    hostile: tuple[str, str], command: str, tmp_path: Path
) -> None:
    path, kind = hostile
    out = tmp_path / "out.bin"
    result = CliRunner().invoke(app, COMMANDS[command](path, str(out)))
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    assert result.exit_code == 2, result.output
    lines = [line for line in result.output.splitlines() if line.strip()]
    refusal = [line for line in lines if path in line and kind in line]
    assert refusal, result.output
    assert "only regular files are read" in refusal[0]
    assert not out.exists()


@pytest.mark.parametrize(
    ("option", "what"),
    [("-c", "a catalog file"), ("--world", "a world file"), (None, "a mission script")],
)
def test_a_huge_text_input_is_refused_before_it_is_read(
    tmp_path: Path, option: str | None, what: str
) -> None:
    huge = tmp_path / "huge.txt"
    with open(huge, "wb") as f:  # sparse: costs no disk
        f.truncate(TEXT_LIMIT + 1)
    args = ["run", str(huge)] if option is None else ["run", str(MISSION), option, str(huge)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2
    assert f"{huge}: error: too large for {what}: 16.0 MB" in result.output


def test_the_limit_holds_while_reading_a_file_that_says_it_is_empty() -> None:
    # /proc files are regular, report size 0, and have content: the read itself is bounded.
    status = Path("/proc/self/status")
    if not status.exists():
        pytest.skip("no /proc here")
    assert regular_file(status, "a catalog file", CatalogError) == 0
    with pytest.raises(CatalogError, match="too large for a catalog file: over 16 bytes"):
        read_bytes(status, "a catalog file", CatalogError, limit=16)
    assert read_bytes(status, "a catalog file", CatalogError).startswith(b"Name:")


def test_text_that_is_not_utf8_names_line_and_column(tmp_path: Path) -> None:
    bad = tmp_path / "m.py"
    bad.write_bytes(b"x = 1\ny = '\xff'\n")
    with pytest.raises(MissionError) as caught:
        read_text(bad, "a mission script", MissionError)
    assert str(caught.value) == f"{bad}:2:6: error: not UTF-8 text (byte 11)"
