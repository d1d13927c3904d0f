"""Recordings named by URL (`s3://bucket/flights/`, `gs://...`, `https://...`): fsspec.

fsspec is what Ray users already read data with (Ray Data, pyarrow and pandas all open
`s3://` through it), and it knows every store through one API; which backend a scheme
needs (s3fs, gcsfs, adlfs...) is the user's to install, and fsspec's own message names
it. fsspec is optional (`pip install "aeroexec[ray]"`) and imported only when an
argument is a URL.

A worker copies one recording at a time to a local temporary file (streaming, 1 MiB at
a time, never the whole file in memory), replays it and deletes it: replay reads a file
several times and seeks in it, which object stores do badly, and the copy is made by
the worker that replays it, so the driver never touches the bytes.
"""

from __future__ import annotations

import re
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path, PurePosixPath
from types import ModuleType
from typing import Any

from aeroexec.errors import AeroexecError, Mark, RecordingError

_URL = re.compile(r"[A-Za-z][A-Za-z0-9+.-]*://")
_GLOB_CHARS = frozenset("*?[")
_COPY_BUFFER = 1 << 20


def is_url(text: str) -> bool:
    """`s3://b/k.mcap`, `file:///x.mcap`: a scheme and `://` (a Windows drive is not)."""
    return _URL.match(text) is not None


def _fsspec() -> ModuleType:
    try:
        import fsspec  # lazy: only URL arguments need it
    except ImportError:
        raise AeroexecError(
            "recordings named by URL need fsspec: pip install 'aeroexec[ray]'"
        ) from None
    return fsspec


def filesystem(url: str) -> tuple[Any, str]:
    """fsspec's filesystem for `url` and the path inside it."""
    fsspec = _fsspec()
    try:
        return fsspec.core.url_to_fs(url)
    except ImportError as exc:  # the scheme's backend is not installed: fsspec names it
        raise RecordingError(f"cannot read: {exc}", Mark(url)) from None
    except (ValueError, OSError) as exc:
        raise RecordingError(f"cannot read: {exc}", Mark(url)) from None


def expand_url(
    argument: str, suffixes: tuple[str, ...], empty: str
) -> list[tuple[str, str | None]]:
    """What a URL argument names, like a local one: a directory gives its recordings
    (`suffixes`, sorted; `empty` says there are none), a pattern its matches (sorted),
    anything else itself (read, and found missing if it is, by the worker). Pairs of
    (URL, error or None)."""
    try:
        fs, path = filesystem(argument)
    except RecordingError as exc:  # a scheme fsspec does not know, a backend not installed
        return [(argument, exc.message)]
    globbing = bool(_GLOB_CHARS & set(path))
    if not globbing and PurePosixPath(path).suffix.lower() in suffixes:
        return [(argument, None)]  # a recording: asking the store costs a request per file
    try:
        if globbing:
            found = fs.glob(path, detail=True)  # detail: no request per match to tell files
            matches = sorted(p for p, info in found.items() if info.get("type") != "directory")
            if not matches:
                return [(argument, "no recordings match this pattern")]
            return [(_url(fs, argument, p), None) for p in matches]
        if fs.isdir(path):
            found = sorted(
                entry["name"]
                for entry in fs.ls(path, detail=True)
                if entry.get("type") == "file"
                and PurePosixPath(entry["name"]).suffix.lower() in suffixes
            )
            if not found:
                return [(argument, empty)]
            return [(_url(fs, argument, p), None) for p in found]
    except Exception as exc:  # a store's own errors (network, permissions) are not OSError
        return [(argument, f"cannot list: {_reason(exc)}")]
    return [(argument, None)]


def _url(fs: Any, argument: str, path: str) -> str:
    """A listed path as a URL of the argument's scheme (some stores list bare keys)."""
    if is_url(path):
        return path
    url = fs.unstrip_protocol(path)
    return str(url) if is_url(str(url)) else f"{argument.split('://', 1)[0]}://{path}"


@contextmanager
def fetched(url: str) -> Iterator[str]:
    """A local copy of the recording at `url`, under its own file name (so a `.bag`
    stays a bag), removed afterwards."""
    fs, path = filesystem(url)
    name = PurePosixPath(path).name or "recording.mcap"
    with tempfile.TemporaryDirectory(prefix="aeroexec-fetch-") as directory:
        local = Path(directory) / name
        try:
            with fs.open(path, "rb") as source, open(local, "wb") as target:
                shutil.copyfileobj(source, target, _COPY_BUFFER)
        except FileNotFoundError:
            raise RecordingError("cannot read: no such file", Mark(url)) from None
        except IsADirectoryError:
            raise RecordingError("cannot read: is a directory", Mark(url)) from None
        except Exception as exc:  # a store's own errors (network, permissions) too
            raise RecordingError(f"cannot read: {_reason(exc)}", Mark(url)) from None
        yield str(local)


def _reason(exc: Exception) -> str:
    text = str(exc)
    return text if isinstance(exc, OSError) and text else f"{type(exc).__name__}: {text}"
