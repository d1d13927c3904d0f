"""Paths that lead nowhere, or into a directory that cannot be read, where aeroexec
expands its inputs (`verify` catalogs and `--mission`, `replay`).

Every command expands globs and directories through `aeroexec.inputs.glob_files` /
`directory_files`, so each of these is the same one line naming the place, exit code 2,
and the inputs that could be read are still checked:

* an unreadable directory given to `replay` (once a PermissionError traceback);
* `verify 'dir/*.yaml'` on an unreadable directory (once "no catalog matches this
  pattern");
* an unreadable subdirectory under `**` (once skipped in silence: a check that passed
  without looking at part of its input);
* a symlink loop (once "no such file").

The tests run as root, which reads any directory whatever its mode: the kernel's refusal
is simulated in process by refusing to list the locked directories (os.scandir and
os.listdir, the calls through which Python lists a directory).
"""

from __future__ import annotations

import errno
import json
import os
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.cli import app

REPO = Path(__file__).resolve().parents[1]
CATALOG = REPO / "catalog" / "default.yaml"
MISSION = REPO / "missions" / "appendix_c.py"
RECORDING = REPO / "recordings" / "appendix_c-v0.1.0.mcap"
DENIED = "cannot read this directory: Permission denied"

runner = CliRunner()


def cli(*args: str) -> tuple[int, str, list[str]]:
    result = runner.invoke(app, list(args))
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(
        result.exception
    )
    assert "Traceback" not in result.output
    return result.exit_code, result.stdout, result.stderr.splitlines()


@pytest.fixture
def lock(monkeypatch: pytest.MonkeyPatch) -> Callable[[Path], None]:
    """`lock(directory)`: listing it fails with EACCES, as for a user without read
    permission on it."""
    locked: set[str] = set()
    real_scandir, real_listdir = os.scandir, os.listdir

    def refuse(path: object) -> None:
        if isinstance(path, (str, bytes, os.PathLike)):
            name = os.path.abspath(os.fsdecode(path) or os.curdir)
            if name in locked:
                raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), name)

    def scandir(path: object = ".") -> object:
        refuse(path)
        return real_scandir(path)  # type: ignore[arg-type]

    def listdir(path: object = ".") -> list[str]:
        refuse(path)
        return real_listdir(path)  # type: ignore[arg-type]

    monkeypatch.setattr(os, "scandir", scandir)
    monkeypatch.setattr(os, "listdir", listdir)
    return lambda directory: locked.add(str(directory.resolve()))


@pytest.fixture
def tree(tmp_path: Path) -> Path:
    """root/{good,locked}/ each with a catalog, a mission and a recording."""
    for name in ("good", "locked"):
        directory = tmp_path / "root" / name
        directory.mkdir(parents=True)
        shutil.copy(CATALOG, directory / "catalog.yaml")
        shutil.copy(MISSION, directory / "mission.py")
        shutil.copy(RECORDING, directory / "flight.mcap")
    return tmp_path / "root"


# -- an unreadable directory named directly ---------------------------------------------
def test_replay_of_an_unreadable_directory_is_one_line(
    tree: Path, lock: Callable[[Path], None]
) -> None:
    lock(tree / "locked")
    code, _, err = cli("replay", str(tree / "locked"))
    assert code == 2
    assert err == [f"{tree / 'locked'}: error: {DENIED}"]


def test_verify_pattern_in_an_unreadable_directory_says_so(
    tree: Path, lock: Callable[[Path], None]
) -> None:
    lock(tree / "locked")
    code, _, err = cli("verify", str(tree / "locked" / "*.yaml"))
    assert code == 2
    assert err == [f"{tree / 'locked'}: error: {DENIED}"]


def test_verify_mission_pattern_in_an_unreadable_directory_says_so(
    tree: Path, lock: Callable[[Path], None]
) -> None:
    lock(tree / "locked")
    code, _, err = cli("verify", str(CATALOG), "--mission", str(tree / "locked" / "*.py"))
    assert code == 2
    assert err == [f"{tree / 'locked'}: error: {DENIED}"]


# -- an unreadable subdirectory under ** -------------------------------------------------
def test_verify_reports_an_unreadable_subdirectory_under_double_star(
    tree: Path, lock: Callable[[Path], None]
) -> None:
    lock(tree / "locked")
    code, out, err = cli("verify", str(tree / "**" / "*.yaml"), "--format", "json")
    assert code == 2  # an input could not be read: not a pass
    assert err == [f"{tree / 'locked'}: error: {DENIED}"]
    files = {f["file"] for f in json.loads(out)["findings"]}
    assert files == {str(tree / "good" / "catalog.yaml")}  # the readable one: verified


def test_verify_missions_report_an_unreadable_subdirectory_under_double_star(
    tree: Path, lock: Callable[[Path], None]
) -> None:
    lock(tree / "locked")
    code, _, err = cli("verify", str(CATALOG), "--mission", str(tree / "**" / "*.py"))
    assert code == 2
    assert err == [f"{tree / 'locked'}: error: {DENIED}"]


def test_replay_reports_an_unreadable_subdirectory_under_double_star(
    tree: Path, lock: Callable[[Path], None]
) -> None:
    lock(tree / "locked")
    code, out, err = cli("replay", str(tree / "**" / "*.mcap"))
    assert code == 2
    assert err == [f"{tree / 'locked'}: error: {DENIED}"]
    assert "flight.mcap" in out  # the readable one was replayed all the same


def test_glob_files_agrees_with_glob_where_everything_is_readable(tree: Path) -> None:
    import glob

    from aeroexec.inputs import glob_files

    (tree / "good" / ".hidden").mkdir()
    (tree / "good" / ".hidden" / "x.yaml").write_text("")
    (tree / "good" / ".dot.yaml").write_text("")
    for pattern in ("**/*.yaml", "*/*.py", "**", "good/*", "*/.*", "*/.hidden/*"):
        found = glob_files(str(tree / pattern))
        expected = [
            m for m in glob.glob(str(tree / pattern), recursive=True) if not os.path.isdir(m)
        ]
        assert found.files == sorted(expected), pattern
        assert found.unreadable == []


# -- symlink loops and dangling symlinks ------------------------------------------------
@pytest.fixture
def loop(tmp_path: Path) -> Path:
    (tmp_path / "a.yaml").symlink_to(tmp_path / "b.yaml")
    (tmp_path / "b.yaml").symlink_to(tmp_path / "a.yaml")
    return tmp_path / "a.yaml"


LOOP = "is a symlink loop (too many levels of symbolic links)"


@pytest.mark.parametrize(
    "command",
    [
        lambda p: ["verify", p],
        lambda p: ["verify", str(CATALOG), "--mission", p],
        lambda p: ["run", str(MISSION), "--catalog", p],
        lambda p: ["replay", p],
        lambda p: ["info", p],
    ],
    ids=["verify", "verify --mission", "run --catalog", "replay", "info"],
)
def test_a_symlink_loop_is_called_one(loop: Path, command: Callable[[str], list[str]]) -> None:
    code, _, err = cli(*command(str(loop)))
    assert code == 2
    assert err == [f"{loop}: error: {LOOP}"]


def test_a_symlink_loop_matched_by_a_pattern_is_reported(loop: Path) -> None:
    code, _, err = cli("verify", str(loop.parent / "*.yaml"))
    assert code == 2
    assert err == [
        f"{loop.parent / 'a.yaml'}: error: {LOOP}",
        f"{loop.parent / 'b.yaml'}: error: {LOOP}",
    ]


def test_a_dangling_symlink_names_its_target(tmp_path: Path) -> None:
    link = tmp_path / "mission.py"
    link.symlink_to(tmp_path / "gone.py")
    code, _, err = cli("verify", str(CATALOG), "--mission", str(link))
    assert code == 2
    assert err == [f"{link}: error: is a dangling symlink (to {str(tmp_path / 'gone.py')!r})"]


# -- a file in a directory that cannot be searched ---------------------------------------
@pytest.fixture
def unsearchable(monkeypatch: pytest.MonkeyPatch, tree: Path) -> Path:
    """root/locked as for a user without search (x) permission on it: nothing inside
    can be looked up or opened (Path.exists() and Path.is_dir() raise PermissionError
    then, they do not return False)."""
    locked = str((tree / "locked").resolve())

    def guard(real: Callable[..., object]) -> Callable[..., object]:
        def call(path: object, *args: object, **kwargs: object) -> object:
            if isinstance(path, (str, os.PathLike)):
                name = os.path.abspath(os.fsdecode(path))
                if name.startswith(locked + os.sep) or (
                    name == locked and real in (os.scandir, os.listdir)
                ):
                    raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(path))
            return real(path, *args, **kwargs)

        return call

    for name in ("stat", "lstat", "open", "scandir", "listdir"):
        monkeypatch.setattr(os, name, guard(getattr(os, name)))
    return tree / "locked"


@pytest.mark.parametrize(
    "command",
    [
        lambda d, out: ["replay", str(d / "flight.mcap")],
        lambda d, out: ["info", str(d / "flight.mcap")],
        lambda d, out: ["verify", str(d / "catalog.yaml")],
        lambda d, out: ["verify", str(CATALOG), "--mission", str(d / "mission.py")],
    ],
    ids=["replay", "info", "verify", "verify --mission"],
)
def test_a_file_in_an_unsearchable_directory_is_one_line(
    unsearchable: Path, tmp_path: Path, command: Callable[[Path, Path], list[str]]
) -> None:
    code, _, err = cli(*command(unsearchable, tmp_path / "out"))
    assert code == 2
    assert len(err) == 1, err
    assert err[0].startswith(f"{unsearchable}{os.sep}")
    assert err[0].endswith("error: cannot read: Permission denied")


def test_any_path_the_system_refuses_is_one_line_not_a_traceback(
    unsearchable: Path, tmp_path: Path
) -> None:
    """Where no reader of aeroexec.inputs stands guard (here `view`'s check of its
    output path), the command's edge still turns the refusal into one line."""
    shutil.copy(RECORDING, tmp_path / "flight.mcap")
    output = unsearchable / "view.rrd"
    code, _, err = cli("view", str(tmp_path / "flight.mcap"), "--output", str(output))
    assert code == 2
    assert err == [f"{output}: error: Permission denied"]
