"""The typer application object and the helpers every command shares.

Commands live in their own modules (`cli/<name>_cmd.py`) and register on `app`; they
stay thin: parse, call the library, format, set the exit code.
"""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable
from typing import Any, TypeVar

import typer

from aeroexec import __version__
from aeroexec.errors import AeroexecError, OutputLost
from aeroexec.interrupts import Interrupted, signals_as_interrupts
from aeroexec.interrupts import check as check_interrupts

app = typer.Typer(
    name="aeroexec",
    help=(
        "Behavior management for a drone's executive layer (after the 2017 Aerostack "
        "design): run missions on a deterministic core, record them to MCAP, verify "
        "catalogs, replay and diff recordings, fly over MAVLink, view in Rerun.\n\n"
        "Exit codes: 0 success, 1 the check found problems (or the mission failed), "
        "2 the input could not be read."
    ),
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)

F = TypeVar("F", bound=Callable[..., Any])


def _version(value: bool) -> None:
    if value:
        typer.echo(f"aeroexec {__version__}")
        raise typer.Exit(0)


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    """aeroexec: behavior management for a drone's executive layer."""


def error_line(message: str) -> None:
    """One line on stderr: what the user must fix."""
    typer.echo(message, err=True)


def guarded(func: F) -> F:
    """Turn aeroexec's input errors (and outputs it could not write) into one stderr
    line and exit code 2 (no traceback), and SIGINT/SIGTERM/SIGHUP into a clean stop:
    the command's `finally` blocks finish or remove its output, then one line and exit
    code 128 + signal."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            with signals_as_interrupts():
                result = func(*args, **kwargs)
                # A signal that came after the last safe point still stops with 128+N
                # (the command's outputs are complete by now).
                check_interrupts()
                return result
        except Interrupted as exc:
            error_line(f"aeroexec: {exc.line()}")
            raise typer.Exit(exc.exit_code) from None
        except (AeroexecError, OutputLost) as caught:
            exc = caught.error if isinstance(caught, OutputLost) else caught
            text = str(exc)
            if exc.mark is None:
                text = f"aeroexec: error: {text}"
            error_line(text)
            raise typer.Exit(2) from None
        except BrokenPipeError:
            # `aeroexec ... | head` closed the pipe: not an error worth a traceback.
            sys.stderr.close()
            raise typer.Exit(0) from None

    return wrapper  # type: ignore[return-value]
