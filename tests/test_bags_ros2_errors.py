"""ROS 2 bags that cannot be read: one line naming the bag, exit code 2, no output file
(`aeroexec import`), whatever the storage or the damage."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from ros2_support import SERVICES_DB3, SERVICES_MCAP, as_directory
from typer.testing import CliRunner

from aeroexec.bags import import_bag
from aeroexec.cli import app


def _cases(root: Path) -> dict[str, tuple[Path, str]]:
    empty = root / "empty.db3"
    empty.write_bytes(b"")
    garbage = root / "garbage.mcap"
    garbage.write_bytes(bytes(range(256)) * 20)
    not_db = root / "garbage.db3"
    not_db.write_bytes(bytes(range(256)) * 20)
    no_meta = root / "rosbag2_no_meta"
    no_meta.mkdir()
    bad_meta = root / "rosbag2_bad_meta"
    bad_meta.mkdir()
    (bad_meta / "metadata.yaml").write_text("rosbag2_bagfile_information: [\n")
    lost = as_directory(SERVICES_MCAP, root / "rosbag2_lost_file")
    for storage in lost.glob("*.mcap"):
        storage.unlink()
    cut_mcap = root / "cut.mcap"
    cut_mcap.write_bytes(SERVICES_MCAP.read_bytes()[:6000])
    cut_db3 = root / "cut.db3"
    cut_db3.write_bytes(SERVICES_DB3.read_bytes()[:12000])
    return {
        "empty db3": (empty, "empty file: not a ROS 2 bag"),
        "not MCAP": (garbage, "not an MCAP file (no MCAP magic)"),
        "not sqlite": (not_db, "not a readable ROS 2 bag: Cannot open database"),
        "directory without metadata": (no_meta, "a directory, but not a rosbag2 bag"),
        "bad metadata.yaml": (bad_meta, "not a readable ROS 2 bag: Could not load YAML"),
        "storage file missing": (lost, "not a readable ROS 2 bag: Some database files are missing"),
        "MCAP cut short": (cut_mcap, "not a readable ROS 2 bag: File end magic is invalid"),
        "sqlite3 cut short": (cut_db3, "not a readable ROS 2 bag: Cannot open database"),
        "missing": (root / "nothere.db3", "no such file or directory"),
    }


CASES = [
    "empty db3",
    "not MCAP",
    "not sqlite",
    "directory without metadata",
    "bad metadata.yaml",
    "storage file missing",
    "MCAP cut short",
    "sqlite3 cut short",
    "missing",
]


@pytest.mark.parametrize("case", CASES)
def test_unreadable_ros2_bags_give_one_line_and_exit_2(case: str, tmp_path: Path) -> None:
    path, says = _cases(tmp_path)[case]
    out = tmp_path / "out"
    out.mkdir()
    result = CliRunner().invoke(app, ["import", str(path), "-o", str(out / "x.mcap")])
    assert result.exit_code == 2
    assert result.stdout == ""
    assert result.stderr.startswith(f"{path}: error: {says}"), result.stderr
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.stderr
    assert list(out.iterdir()) == []


def test_an_aeroexec_recording_is_not_a_bag(tmp_path: Path) -> None:
    recording = tmp_path / "imported.mcap"
    import_bag(SERVICES_MCAP, recording)
    copy = tmp_path / "again.mcap"
    result = CliRunner().invoke(app, ["import", str(recording), "-o", str(copy)])
    assert result.exit_code == 2
    assert result.stderr == f"{recording}: error: already an aeroexec recording, not a ROS 2 bag\n"
    assert not copy.exists()


def test_types_on_a_ros1_bag_is_refused(tmp_path: Path) -> None:
    bag = Path(__file__).parent / "fixtures" / "bags" / "ros1_turtlesim_example_lz4.bag"
    types = tmp_path / "types"
    shutil.copytree(
        Path(__file__).parent.parent / "aeroexec/data/msg_ros2/std_srvs", types / "std_srvs"
    )
    result = CliRunner().invoke(
        app, ["import", str(bag), "-o", str(tmp_path / "x.mcap"), "--types", str(types)]
    )
    assert result.exit_code == 2
    assert result.stderr.startswith(f"{types}: error: --types is for ROS 2 bags")
