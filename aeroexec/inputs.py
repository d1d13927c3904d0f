"""Reading a file the user named, safely: only regular files, and never without bound.

Every reader of user input goes through here (catalogs, missions, worlds, bag mappings,
recordings, bags), so that `/dev/zero` given as a catalog is refused at once instead of
growing a string to the size of memory, and a FIFO given as a recording is refused
instead of blocking forever in `open()`.

* `regular_file(path, what, error)`: the file's size, after checking that `path` names a
  regular file. The check is made on a descriptor opened with `O_NONBLOCK`, so opening a
  FIFO without a writer returns at once instead of waiting for one.
* `read_bytes` / `read_text`: the whole file, refused above `limit` bytes. The limit is
  enforced while reading too (a file in /proc says size 0 and then has content).
* `glob_files` / `directory_files`: the files a glob pattern (`**` recursive) or a
  directory names, and every place that stopped the search (a directory that cannot be
  listed, a match that is a symlink loop or dangling): `glob.glob` skips those in
  silence, so an unreadable `flights/` looked like "no match" and an unreadable
  subdirectory under `**` vanished from a check that then passed.
* `pending_contents(contents)`: within it, the files it names read as the bytes it
  gives (`verify --diff` runs its later fix passes on fixed contents it never writes);
  `current_bytes(path)` reads a file as the readers here would.
* `missing(path)`: why a path names no file ("no such file", "is a symlink loop",
  "is a dangling symlink"), for the one line that says so.

Errors are the caller's `AeroexecError` subclass, with the file (and, for text that is
not UTF-8, the line and column of the first bad byte) as the mark.
"""

from __future__ import annotations

import errno
import fnmatch
import glob
import os
import stat
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field
from pathlib import Path

from aeroexec.errors import AeroexecError, Mark

#: The largest text input read whole (catalog, mission, world, mapping): far above any
#: real one (the largest Aerostack catalog is 12 kB), far below what hurts.
TEXT_LIMIT = 16 * 1024 * 1024

_KINDS = (
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


def _size_text(size: int) -> str:
    for unit, scale in (("GB", 1 << 30), ("MB", 1 << 20), ("kB", 1 << 10)):
        if size >= scale:
            return f"{size / scale:.1f} {unit}"
    return f"{size} bytes"


def _not_regular(mode: int) -> str:
    for test, name in _KINDS:
        if test(mode):
            return name
    return "not a regular file"


def _open(path: str | os.PathLike[str], what: str, error: type[AeroexecError]) -> int:
    """A read-only descriptor on a regular file (the caller closes it)."""
    file = str(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise error(missing(file), Mark(file)) from None
    except IsADirectoryError:
        raise error(f"is a directory, not {what}", Mark(file)) from None
    except OSError as exc:
        raise error(_os_problem(exc), Mark(file)) from None
    try:
        mode = os.fstat(fd).st_mode
    except OSError as exc:
        os.close(fd)
        raise error(f"cannot read: {exc.strerror or exc}", Mark(file)) from None
    if stat.S_ISDIR(mode):
        os.close(fd)
        raise error(f"is a directory, not {what}", Mark(file))
    if not stat.S_ISREG(mode):
        os.close(fd)
        raise error(
            f"is {_not_regular(mode)}, not {what} (only regular files are read)", Mark(file)
        )
    return fd


def regular_file(path: str | os.PathLike[str], what: str, error: type[AeroexecError]) -> int:
    """The size of `path` if it is a regular file, else `error` (one line)."""
    fd = _open(path, what, error)
    try:
        return os.fstat(fd).st_size
    finally:
        os.close(fd)


def is_directory(path: str | os.PathLike[str]) -> bool:
    """Does `path` name a directory? False, not PermissionError, where a parent cannot
    be searched (`Path.is_dir` raises then): the reader says why in its one line."""
    try:
        return stat.S_ISDIR(os.stat(path).st_mode)
    except (OSError, ValueError):
        return False


def is_regular_file(path: str | os.PathLike[str]) -> bool:
    """Does `path` name a regular file (without opening it)?"""
    try:
        return stat.S_ISREG(os.stat(path).st_mode)
    except (OSError, ValueError):
        return False


#: Path as named -> the bytes it reads as (`pending_contents`).
_PENDING: ContextVar[Mapping[str, bytes] | None] = ContextVar("pending_contents", default=None)


@contextmanager
def pending_contents(contents: Mapping[str, bytes]) -> Iterator[None]:
    """Within this block, the files `contents` names (as their path is written) read as
    its bytes, on disk or not: a later change of `contents` shows at the next read."""
    token = _PENDING.set(contents)
    try:
        yield
    finally:
        _PENDING.reset(token)


def current_bytes(path: str | os.PathLike[str]) -> bytes:
    """The file's bytes as `read_bytes` sees them (pending contents first), without
    its checks: for a file already read once. `OSError` if it cannot be read now."""
    contents = _PENDING.get()
    pending = contents.get(str(path)) if contents is not None else None
    return pending if pending is not None else Path(path).read_bytes()


def read_bytes(
    path: str | os.PathLike[str],
    what: str,
    error: type[AeroexecError],
    limit: int = TEXT_LIMIT,
) -> bytes:
    """The bytes of the regular file `path`, at most `limit` of them (else `error`)."""
    file = str(path)
    contents = _PENDING.get()
    pending = contents.get(file) if contents is not None else None
    if pending is not None and len(pending) <= limit:
        return pending
    fd = _open(path, what, error)
    too_large = f"too large for {what}: over {_size_text(limit)}"
    try:
        size = os.fstat(fd).st_size
        if size > limit:
            raise error(
                f"too large for {what}: {_size_text(size)} (the limit is {_size_text(limit)})",
                Mark(file),
            )
        os.set_blocking(fd, True)
        with os.fdopen(fd, "rb", closefd=False) as stream:
            data = stream.read(limit + 1)
    except OSError as exc:
        raise error(f"cannot read: {exc.strerror or exc}", Mark(file)) from None
    finally:
        os.close(fd)
    if len(data) > limit:
        raise error(too_large, Mark(file))
    return data


def read_text(
    path: str | os.PathLike[str],
    what: str,
    error: type[AeroexecError],
    limit: int = TEXT_LIMIT,
) -> str:
    """The UTF-8 text of the regular file `path` (see `read_bytes`); text that is not
    UTF-8 is `error` at the line and column of the first bad byte."""
    data = read_bytes(path, what, error, limit)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"not UTF-8 text (byte {exc.start})", byte_mark(str(path), exc)) from None


def byte_mark(file: str, exc: UnicodeDecodeError) -> Mark:
    """Line and column (in characters) of the first byte that is not UTF-8."""
    data = bytes(exc.object)
    start = data.rfind(b"\n", 0, exc.start) + 1
    column = len(data[start : exc.start].decode("utf-8", "replace")) + 1
    return Mark(file, data.count(b"\n", 0, exc.start) + 1, column)


# -- which files a command line names ----------------------------------------------------
def _os_problem(exc: OSError) -> str:
    if exc.errno == errno.ELOOP:
        return "is a symlink loop (too many levels of symbolic links)"
    return f"cannot read: {exc.strerror or exc}"


def missing(path: str | os.PathLike[str]) -> str:
    """Why `path` names no file: "no such file", "is a symlink loop", "is a dangling
    symlink (to ...)", or what the system said."""
    try:
        os.stat(path)
    except FileNotFoundError:
        try:
            target = os.readlink(path)
        except OSError:
            return "no such file"
        return f"is a dangling symlink (to {target!r})"
    except OSError as exc:
        return _os_problem(exc)
    except ValueError:  # a NUL in the name
        return "no such file"
    return "no such file"  # it appeared since: say what the caller saw


@dataclass(frozen=True, slots=True)
class Unreadable:
    """A place the search for inputs could not look into (`problem`: one line)."""

    path: str
    problem: str


@dataclass(frozen=True, slots=True)
class Expansion:
    """What a pattern or directory names: `files` (sorted; anything but a directory, so
    that a FIFO matched is refused by the reader in its own words) and `unreadable`, the
    places that stopped the search, in the order met."""

    files: list[str] = field(default_factory=list)
    unreadable: list[Unreadable] = field(default_factory=list)


def has_magic(text: str) -> bool:
    return glob.has_magic(text)


#: Tells a directory that is one input (a rosbag2 bag: a directory with its metadata.yaml)
#: from a directory of inputs; such a directory is kept like a file.
WholeDirectory = Callable[[str], bool]


def directory_files(
    path: str | os.PathLike[str],
    suffixes: tuple[str, ...] = (),
    whole: WholeDirectory | None = None,
) -> Expansion:
    """The files directly inside the directory `path` whose name ends with one of
    `suffixes` (any case; every file without them), and the directories inside it that
    `whole` says are one input each, sorted."""
    found = Expansion()
    for name in _names(str(path), found):
        inside = os.path.join(str(path), name)
        if not suffixes or name.lower().endswith(suffixes) or (whole and whole(inside)):
            _keep(inside, found, whole)
    found.files.sort()
    return found


def glob_files(pattern: str, whole: WholeDirectory | None = None) -> Expansion:
    """The files `pattern` matches, as `glob.glob(pattern, recursive=True)` finds them
    (hidden names only for a part that starts with '.'; `**` is any number of
    directories), and the directories it matches that `whole` says are one input each,
    sorted; plus the directories that could not be listed and the matches that are
    symlink loops or dangling symlinks."""
    found = Expansion()
    head, parts = _split(pattern)
    bases = [head]
    for index, part in enumerate(parts):
        last = index == len(parts) - 1
        following: list[str] = []
        for base in bases:
            if part == "**":
                for directory in _tree(base, found):
                    following.append(directory)
                    if last:
                        following.extend(
                            os.path.join(directory, name)
                            for name in _names(directory, found)
                            if not _hidden(name)
                        )
            elif glob.has_magic(part):
                names = [n for n in _names(base, found) if _matches(n, part)]
                following.extend(os.path.join(base, name) for name in names)
            elif part:
                following.append(os.path.join(base, part))
        if not last:
            following = [p for p in following if _is_directory(p, found)]
        bases = list(dict.fromkeys(following))
    for path in sorted(bases):
        _keep(path, found, whole)
    found.files.sort()
    found.unreadable[:] = dict.fromkeys(found.unreadable)  # `**` lists a directory twice
    return found


def _split(pattern: str) -> tuple[str, list[str]]:
    """(the anchor: '' or '/', the parts after it)."""
    head = os.sep if pattern.startswith(os.sep) else ""
    parts = [p for p in pattern.split(os.sep) if p]
    return head, parts or [""]


def _hidden(name: str) -> bool:
    return name.startswith(".")


def _matches(name: str, part: str) -> bool:
    if _hidden(name) and not _hidden(part):
        return False
    return fnmatch.fnmatch(name, part)


def _names(directory: str, found: Expansion) -> list[str]:
    """The names in `directory` ('' is the current one); one that cannot be listed is
    noted in `found`."""
    try:
        with os.scandir(directory or os.curdir) as entries:
            return sorted(entry.name for entry in entries)
    except OSError as exc:
        problem = f"cannot read this directory: {exc.strerror or exc}"
        if exc.errno == errno.ELOOP:
            problem = _os_problem(exc)
        found.unreadable.append(Unreadable(directory or os.curdir, problem))
        return []


def _is_directory(path: str, found: Expansion) -> bool:
    """Is `path` a directory to search? One that cannot be reached for want of
    permission is noted; a symlink loop or a dangling link is no directory (it is
    reported only where it is a match: `_keep`)."""
    try:
        return stat.S_ISDIR(os.stat(path).st_mode)
    except OSError as exc:
        if exc.errno in (errno.EACCES, errno.EPERM):
            found.unreadable.append(Unreadable(path, _os_problem(exc)))
        return False
    except ValueError:
        return False


def _tree(base: str, found: Expansion) -> Iterator[str]:
    """`base` and every directory below it, hidden ones left out, each once (a symlink
    back up the tree is followed once, not forever)."""
    seen: set[tuple[int, int]] = set()
    pending = [base]
    while pending:
        directory = pending.pop()
        try:
            info = os.stat(directory or os.curdir)
        except OSError as exc:
            found.unreadable.append(Unreadable(directory, _os_problem(exc)))
            continue
        if (info.st_dev, info.st_ino) in seen:
            continue
        seen.add((info.st_dev, info.st_ino))
        yield directory
        below = [
            os.path.join(directory, name) for name in _names(directory, found) if not _hidden(name)
        ]
        pending.extend(reversed([p for p in below if _is_directory(p, found)]))


def _keep(path: str, found: Expansion, whole: WholeDirectory | None = None) -> None:
    """Add the match `path` to the files unless it is a directory (other than one that
    `whole` takes as one input); one that does not lead to a file (a symlink loop, a
    dangling symlink) is unreadable."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        if os.path.islink(path):
            found.unreadable.append(Unreadable(path, missing(path)))
        return
    except OSError as exc:
        found.unreadable.append(Unreadable(path, _os_problem(exc)))
        return
    if not stat.S_ISDIR(mode) or (whole is not None and whole(path)):
        found.files.append(path)
