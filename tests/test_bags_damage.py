"""Damaged ROS 1 bags: `info` finds what `import` refuses, in words, and imports follow
the umask.

`info` used to read only a bag's index, so it called complete a bag whose chunks fail
their lz4 checksum; errors from rosbags surfaced as `: AssertionError` or `: 54054`.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_bags_support import TURTLE_LZ4, short_mission
from typer.testing import CliRunner

from aeroexec.bags import import_bag
from aeroexec.bags.info import bag_info
from aeroexec.cli import app
from aeroexec.errors import RecordingError

#: What an error line must not end in: a bare exception name, a number, a tuple's repr.
RAW = re.compile(r"(: [A-Za-z]*(Error|Exception)|: \d+|\(['\"].*['\"],\))$")


@pytest.fixture(scope="module")
def small_bag(tmp_path_factory: pytest.TempPathFactory) -> bytes:
    folder = tmp_path_factory.mktemp("bags")
    return short_mission().write(folder / "m.bag", compression="lz4").read_bytes()


def verdicts(bag: Path, folder: Path) -> tuple[str | None, str | None]:
    """(info's problem, import's error): None where it found none."""
    try:
        report = bag_info(bag)
        seen = report.problem if not report.complete else None
    except RecordingError as exc:
        seen = str(exc)
    try:
        import_bag(bag, folder / "out.mcap")
        refused = None
    except RecordingError as exc:
        refused = str(exc)
    return seen, refused


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(data=st.data())
def test_info_refuses_what_import_refuses_in_words(
    small_bag: bytes, tmp_path_factory: pytest.TempPathFactory, data: st.DataObject
) -> None:
    folder = tmp_path_factory.mktemp("case")
    raw = bytearray(small_bag)
    for _ in range(data.draw(st.integers(1, 6), "flips")):
        raw[data.draw(st.integers(0, len(raw) - 1), "at")] = data.draw(st.integers(0, 255))
    bag = folder / "b.bag"
    bag.write_bytes(bytes(raw))
    seen, refused = verdicts(bag, folder)
    if refused is not None:
        assert seen is not None, f"info called complete a bag import refuses: {refused}"
    for text in (seen, refused):
        if text is not None:
            assert "\n" not in text and not RAW.search(text), text


def damaged_chunk(tmp_path: Path) -> Path:
    """The turtlesim lz4 bag with one byte of its first chunk's data flipped."""
    raw = bytearray(TURTLE_LZ4.read_bytes())
    at = raw.index(b"compression=lz4") + 400  # inside the first chunk's lz4 frame
    raw[at] ^= 0xFF
    path = tmp_path / "flipped.bag"
    path.write_bytes(bytes(raw))
    return path


def test_info_reads_the_chunks_and_says_what_import_will_refuse(tmp_path: Path) -> None:
    bag = damaged_chunk(tmp_path)
    result = CliRunner().invoke(app, ["info", str(bag)])
    assert result.exit_code == 0
    assert "complete:    NO: damaged bag data in the first chunk: LZ4F_" in result.stdout
    assert result.stderr.startswith(f"{bag}: warning: damaged bag: damaged bag data")
    refused = CliRunner().invoke(app, ["import", str(bag), "-o", str(tmp_path / "x.mcap")])
    assert refused.exit_code == 2
    assert "LZ4F_" in refused.stderr and not (tmp_path / "x.mcap").exists()


@pytest.mark.parametrize(
    ("error", "says"),
    [
        (KeyError(54054), "a record refers to id 54054, which is not defined"),
        (AssertionError(), "a message is not what the index says"),
        (ValueError(("Header could not be read from file.",)), "Header could not be read"),
    ],
)
def test_rosbags_errors_become_words(error: Exception, says: str) -> None:
    from aeroexec.bags.bagfile import _reason

    text = _reason(error)
    assert says in text and not RAW.search(text)


@pytest.fixture()
def umask() -> Iterator[int]:
    previous = os.umask(0o027)
    try:
        yield 0o027
    finally:
        os.umask(previous)


def test_imported_and_recovered_files_follow_the_umask(tmp_path: Path, umask: int) -> None:
    out = tmp_path / "turtle.mcap"
    result = CliRunner().invoke(app, ["import", str(TURTLE_LZ4), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert out.stat().st_mode & 0o777 == 0o666 & ~umask  # 0640, not mkstemp's 0600
    fixed = tmp_path / "fixed.mcap"
    assert CliRunner().invoke(app, ["recover", str(out), "-o", str(fixed)]).exit_code == 0
    assert fixed.stat().st_mode & 0o777 == 0o666 & ~umask
