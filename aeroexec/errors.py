"""Exception classes shared by every part of aeroexec.

Library code raises these; the CLI turns them into one line on stderr and exit code 2.
Each carries the place it is about so the message reads like a compiler's.
"""

from __future__ import annotations

from dataclasses import dataclass


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

    def __str__(self) -> str:
        if self.mark is None:
            return self.message
        return f"{self.mark}: error: {self.message}"


class CatalogError(AeroexecError):
    """The catalog cannot be read or violates an error tag."""


class MissionError(AeroexecError):
    """The mission script cannot be read, or misuses the mission API."""


class RecordingError(AeroexecError):
    """A recording (MCAP or bag) cannot be read or written."""


class WorldError(AeroexecError):
    """A simulator world file is malformed."""
