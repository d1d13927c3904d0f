"""Bad bags and bad mappings: one clear line on stderr naming the file, exit code 2, no
traceback, and no half-written output left behind."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_bags_support import AEROSTACK_BAG, THESIS_CATALOG, TURTLE_BZ2, TURTLE_LZ4, short_mission
from typer.testing import CliRunner

from aeroexec.bags import import_bag
from aeroexec.cli import app
from aeroexec.errors import RecordingError


def _invoke(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, list(args))
    assert not isinstance(result.exception, Exception) or isinstance(
        result.exception, SystemExit
    ), repr(result.exception)
    return result.exit_code, result.stdout, result.stderr


def _flip(source: Path, target: Path, start: int, count: int = 64) -> Path:
    data = bytearray(source.read_bytes())
    for i in range(start, start + count):
        data[i] ^= 0xFF
    target.write_bytes(bytes(data))
    return target


def _index_pos(path: Path) -> int:
    data = path.read_bytes()
    at = data.index(b"index_pos=") + len("index_pos=")
    return int(struct.unpack_from("<Q", data, at)[0])


@pytest.fixture
def bad(tmp_path: Path) -> dict[str, tuple[Path, str]]:
    """name -> (file, what the error line says after 'error: ')."""
    real = AEROSTACK_BAG.read_bytes()
    cut = tmp_path / "cut.bag"
    cut.write_bytes(real[: len(real) // 2])
    random = tmp_path / "random.bag"
    random.write_bytes(bytes((i * 7919 + 13) % 256 for i in range(5000)))
    empty = tmp_path / "empty.bag"
    empty.write_bytes(b"")
    folder = tmp_path / "folder.bag"
    folder.mkdir()
    old = tmp_path / "old.bag"
    old.write_bytes(b"#ROSBAG V1.2\n" + real[13:2000])
    header_only = tmp_path / "header_only.bag"
    header_only.write_bytes(real[:20])
    unindexed = tmp_path / "unindexed.bag"
    data = bytearray(real)
    at = data.index(b"index_pos=") + len("index_pos=")
    data[at : at + 8] = bytes(8)
    unindexed.write_bytes(bytes(data))
    index_cut = tmp_path / "index_cut.bag"
    index_cut.write_bytes(real[: _index_pos(AEROSTACK_BAG) + 100])
    return {
        "cut in the middle": (cut, "truncated: the bag's index should start at byte 2913487"),
        "random bytes": (random, "not a ROS 1 bag (it does not start with '#ROSBAG V2.0')"),
        "empty file": (empty, "empty file: not a ROS 1 bag"),
        "directory": (folder, "is a directory, not a ROS 1 bag file"),
        "old format": (old, "ROS bag format version '1.2' is not supported (only 2.0)"),
        "cut in the header": (header_only, "truncated: the file ends inside the bag header"),
        "no index": (unindexed, "the bag has no index (its recording was never closed)"),
        "cut in the index": (index_cut, "damaged bag: Bag index looks damaged"),
        "missing": (tmp_path / "missing.bag", "no such file"),
    }


@pytest.mark.parametrize(
    "case",
    [
        "cut in the middle",
        "random bytes",
        "empty file",
        "directory",
        "old format",
        "cut in the header",
        "no index",
        "cut in the index",
        "missing",
    ],
)
@pytest.mark.parametrize("command", ["import", "info", "replay"])
def test_unreadable_bags_give_one_line_and_exit_2(
    bad: dict[str, tuple[Path, str]], case: str, command: str, tmp_path: Path
) -> None:
    path, says = bad[case]
    target = tmp_path / "out" / "x.mcap"
    target.parent.mkdir()
    args = {
        "import": ("import", str(path), "-o", str(target)),
        "info": ("info", str(path)),
        "replay": ("replay", str(path), "--catalog", str(THESIS_CATALOG)),
    }[command]
    if (command, case) == ("replay", "directory"):
        says = "no *.mcap"  # replay takes folders of recordings
    code, out, err = _invoke(*args)
    assert code == 2
    assert out == ""
    assert err.startswith(f"{path}: error: {says}"), err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert list(target.parent.iterdir()) == []  # nothing written, no partial file


@pytest.mark.parametrize(
    ("source", "offset", "says"),
    [
        (TURTLE_BZ2, 100_000, "damaged bag data in the first chunk: Invalid data stream"),
        (TURTLE_LZ4, 100_000, "damaged bag data in the first chunk: LZ4F_decompress failed"),
        (AEROSTACK_BAG, 1_000_000, "damaged bag data after 464 messages (bag time 1498638128.118"),
    ],
    ids=["bz2", "lz4", "plain"],
)
def test_damaged_chunks_stop_the_import_without_leaving_a_file(
    tmp_path: Path, source: Path, offset: int, says: str
) -> None:
    broken = _flip(source, tmp_path / source.name, offset)
    out = tmp_path / "out"
    out.mkdir()
    code, stdout, err = _invoke("import", str(broken), "-o", str(out / "x.mcap"))
    assert (code, stdout) == (2, "")
    assert err.startswith(f"{broken}: error: {says}"), err
    assert err.count("\n") == 1
    assert list(out.iterdir()) == []


def test_an_output_that_cannot_be_written(tmp_path: Path) -> None:
    target = tmp_path / "no" / "such" / "dir" / "x.mcap"
    code, _, err = _invoke("import", str(TURTLE_BZ2), "-o", str(target))
    assert code == 2
    assert err.startswith(f"{target}: error: cannot write: No such file or directory")


def test_the_output_may_not_be_the_bag(tmp_path: Path) -> None:
    copy = tmp_path / "t.bag"
    copy.write_bytes(TURTLE_BZ2.read_bytes())
    code, _, err = _invoke("import", str(copy), "-o", str(copy))
    assert code == 2 and "would overwrite the bag" in err
    assert copy.read_bytes() == TURTLE_BZ2.read_bytes()


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("topics: [\n", "map.yaml:2:1: error: invalid YAML"),
        ("- 1\n", "map.yaml:1:1: error: a mapping file is a YAML mapping with a `topics:` list"),
        ("version: 1\n", "map.yaml:1:1: error: missing `topics:`"),
        ("version: 2\ntopics: []\n", "map.yaml:1:10: error: unsupported mapping version 2"),
        ("topics: []\ncolour: red\n", "map.yaml:2:1: error: unknown key 'colour' in top level"),
        (
            "topics:\n  - {topic: /a, kind: wind}\n",
            "map.yaml:2:23: error: unknown kind 'wind' (known: behavior_event,",
        ),
        ("topics:\n  - {kind: pose}\n", "map.yaml:2:5: error: a topics entry needs a `topic:`"),
        ("topics:\n  - {topic: a, kind: pose}\n", "map.yaml:2:13: error: topic 'a' must be"),
        ("topics:\n  - {type: Pose, kind: pose}\n", "map.yaml:2:12: error: type 'Pose' must be"),
        ("topics:\n  - {topic: /a, kind: pose, as: x}\n", "map.yaml:2:29: error: unknown key 'as'"),
        ("grace_s: -1\ntopics: []\n", "map.yaml:1:10: error: grace_s must be between 0 and 60"),
        ("drone: a/b\ntopics: []\n", "map.yaml:1:8: error: drone must be one topic name segment"),
    ],
)
def test_mapping_errors_name_file_line_and_column(tmp_path: Path, text: str, says: str) -> None:
    mapping = tmp_path / "map.yaml"
    mapping.write_text(text)
    code, _, err = _invoke(
        "import", str(TURTLE_BZ2), "-o", str(tmp_path / "x.mcap"), "--mapping", str(mapping)
    )
    assert code == 2
    assert err.startswith(f"{tmp_path}/{says}"), err
    assert err.count("\n") == 1
    assert not (tmp_path / "x.mcap").exists()


@pytest.mark.parametrize("drone", ["", "a/b", "ros1", "drone 1"])
def test_bad_drone_names(tmp_path: Path, drone: str) -> None:
    code, _, err = _invoke(
        "import", str(TURTLE_BZ2), "-o", str(tmp_path / "x.mcap"), "--drone", drone
    )
    assert code == 2
    assert err.startswith("--drone: error: drone ")


@pytest.fixture(scope="module")
def small_bag(tmp_path_factory: pytest.TempPathFactory) -> bytes:
    folder = tmp_path_factory.mktemp("fuzz")
    return short_mission().write(folder / "m.bag", compression="lz4").read_bytes()


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(data=st.data())
def test_damage_anywhere_is_an_input_error_or_a_complete_import(
    small_bag: bytes, tmp_path_factory: pytest.TempPathFactory, data: st.DataObject
) -> None:
    """Cut or overwrite a small lz4 bag anywhere: the import either succeeds or raises
    RecordingError, never anything else, and leaves a file only when it succeeds."""
    folder = tmp_path_factory.mktemp("case")
    raw = bytearray(small_bag)
    if data.draw(st.booleans(), "cut"):
        raw = raw[: data.draw(st.integers(0, len(raw) - 1), "at")]
    else:
        start = data.draw(st.integers(0, len(raw) - 1), "start")
        for i in range(start, min(len(raw), start + data.draw(st.integers(1, 32), "n"))):
            raw[i] = data.draw(st.integers(0, 255))
    bag = folder / "b.bag"
    bag.write_bytes(bytes(raw))
    target = folder / "b.mcap"
    try:
        import_bag(bag, target)
    except RecordingError as exc:
        assert "\n" not in str(exc)
        assert not target.exists()
    else:
        assert target.exists()
    assert [p.name for p in folder.iterdir() if p.name.endswith(".partial")] == []
