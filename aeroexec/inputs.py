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

Errors are the caller's `AeroexecError` subclass, with the file (and, for text that is
not UTF-8, the line and column of the first bad byte) as the mark.
"""

from __future__ import annotations

import os
import stat

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
        raise error("no such file", Mark(file)) from None
    except IsADirectoryError:
        raise error(f"is a directory, not {what}", Mark(file)) from None
    except OSError as exc:
        raise error(f"cannot read: {exc.strerror or exc}", Mark(file)) from None
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


def is_regular_file(path: str | os.PathLike[str]) -> bool:
    """Does `path` name a regular file (without opening it)?"""
    try:
        return stat.S_ISREG(os.stat(path).st_mode)
    except (OSError, ValueError):
        return False


def read_bytes(
    path: str | os.PathLike[str],
    what: str,
    error: type[AeroexecError],
    limit: int = TEXT_LIMIT,
) -> bytes:
    """The bytes of the regular file `path`, at most `limit` of them (else `error`)."""
    file = str(path)
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
