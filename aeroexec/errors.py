"""Exception classes shared by every part of aeroexec.

Library code raises these; the CLI turns them into one line on stderr and exit code 2.
Each carries the place it is about so the message reads like a compiler's.
"""

from __future__ import annotations

from dataclasses import dataclass

#: Every character `str.splitlines` breaks on, and the other C0 controls (tab is kept).
_LINE_BREAKING = {
    c: f"\\x{c:02x}" if c < 0x100 else f"\\u{c:04x}"
    for c in [*range(0x20), 0x7F, 0x85, 0x2028, 0x2029]
    if c != 0x09
}
_LINE_BREAKING |= {ord("\n"): "\\n", ord("\r"): "\\r"}


def one_line(text: str) -> str:
    """`text` with line breaks and control characters escaped.

    Messages quote names and keys from the input (`unknown tag '...'`); a key with a
    newline in it must not split a `file:line:col: ...` line in two.
    """
    return text.translate(_LINE_BREAKING)


@dataclass(frozen=True, slots=True)
class Mark:
    """A place in a file: 1-based line and column, as editors and SARIF count them."""

    file: str
    line: int = 0
    column: int = 0

    def __str__(self) -> str:
        if self.line <= 0:
            return self.file
        return f"{self.file}:{self.line}:{self.column}"


class AeroexecError(Exception):
    """Base class: an input problem that the user must fix (exit code 2 at the CLI)."""

    def __init__(self, message: str, mark: Mark | None = None) -> None:
        super().__init__(message)
        self.message = message
        self.mark = mark

    def __reduce__(self) -> tuple[object, ...]:
        # Crosses process boundaries (replay --jobs) with its mark.
        return (type(self), (self.message, self.mark))

    def __str__(self) -> str:
        if self.mark is None:
            return one_line(self.message)
        return one_line(f"{self.mark}: error: {self.message}")


class CatalogError(AeroexecError):
    """The catalog cannot be read or violates an error tag."""


class MissionError(AeroexecError):
    """The mission script cannot be read, or misuses the mission API."""


class RecordingError(AeroexecError):
    """A recording (MCAP or bag) cannot be read or written."""


class WorldError(AeroexecError):
    """A simulator world file is malformed."""


class ConfigError(AeroexecError):
    """The project configuration (`[tool.aeroexec]` or `aeroexec.toml`) is malformed."""


class BehaviorError(AeroexecError):
    """A developer's behaviors cannot be loaded, or a catalog behavior has no code."""


class ViewerError(AeroexecError):
    """The viewer (Rerun's) cannot be started or cannot serve."""


class OutputLost(BaseException):
    """An output file could not be written (a full disk, a file size limit): the command
    must stop, and `error` says what was kept or removed.

    A `BaseException`, like `KeyboardInterrupt`: the writer fails inside the session (the
    recorder is a bus observer), and no mission's or behavior's `except Exception:` may
    swallow it and fly on unrecorded.
    """

    def __init__(self, error: AeroexecError) -> None:
        super().__init__(str(error))
        self.error = error

    def __reduce__(self) -> tuple[object, ...]:
        return (type(self), (self.error,))


class ReportError(AeroexecError):
    """A report to merge (a shard's JSON result) cannot be read, or the shards do not
    make one whole run."""


class PropertyError(AeroexecError):
    """A property file (signal temporal logic) cannot be read: bad YAML, a formula that
    does not parse, a signal no recording has."""


class InjectionError(AeroexecError):
    """A fault to inject (`replay --inject FAULT@WHEN`, `explore --faults`) is not one the
    simulator models, a parameter is unknown or out of range, or WHEN names no moment of
    the recording."""


class FuzzError(AeroexecError):
    """`aeroexec fuzz` cannot use an input: its failure database, a budget, a mission to
    mutate that runs no command."""
