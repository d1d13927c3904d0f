"""The options commands share, declared once so that each reads the same everywhere.

docs/cli.md is their reference and tests/test_cli_vocabulary.py holds every command to
it: `-o/--output FILE` for the one file a command writes, `-c/--catalog FILE`,
`-m/--mission FILE`, `-w/--world FILE`, `-f/--format [text|...]`, `--color
[auto|always|never]`, `-q/--quiet`, `-j/--jobs N`. Each factory takes the help text,
which says what the option means for that command.
"""

from __future__ import annotations

import os
import sys
from enum import Enum
from typing import Any, TypeVar

import typer

from aeroexec.cli.app import say
from aeroexec.errors import AeroexecError
from aeroexec.interrupts import limit_user_code

E = TypeVar("E", bound=Enum)
T = TypeVar("T")


def choices(kind: type[Enum]) -> str:
    """A choice's metavar: its values, `[text|json|junit]`."""
    return "[" + "|".join(str(member.value) for member in kind) + "]"


def output_option(help: str, *, required: bool = False) -> Any:
    return typer.Option(
        ... if required else None,
        "--output",
        "-o",
        metavar="FILE",
        help=help,
        show_default=False,
    )


def output_dir_option(help: str) -> Any:
    return typer.Option(None, "--output-dir", metavar="DIR", help=help, show_default=False)


def deprecated_option(*names: str, instead: str, metavar: str = "FILE") -> Any:
    """An old spelling kept working for existing scripts: hidden from the help, listed
    under "Deprecated spellings" in docs/cli.md, announced on stderr when used."""
    return typer.Option(
        None,
        *names,
        hidden=True,
        metavar=metavar,
        help=f"Deprecated spelling of {instead}.",
        show_default=False,
    )


def replaced(new: T | None, old: T | None, *, new_name: str, old_name: str) -> T | None:
    """The value of an option given in its new or its deprecated spelling (not both)."""
    if old is None:
        return new
    if new is not None:
        raise AeroexecError(f"give {new_name} or {old_name} (its old spelling), not both")
    say("warning", f"{old_name} is deprecated; use {new_name}")
    return old


def catalog_option(help: str) -> Any:
    return typer.Option(None, "--catalog", "-c", metavar="FILE", help=help, show_default=False)


def mission_option(help: str, *, repeatable: bool = False) -> Any:
    return typer.Option(
        [] if repeatable else None,
        "--mission",
        "-m",
        metavar="FILE",
        help=help,
        show_default=False,
    )


def world_option(help: str) -> Any:
    return typer.Option(None, "--world", "-w", metavar="FILE", help=help, show_default=False)


def format_option(kind: type[E], help: str) -> Any:
    """`-f/--format`: the first value (`text`, for people) is the default."""
    return typer.Option(
        next(iter(kind)), "--format", "-f", metavar=choices(kind), help=help, show_default=True
    )


class Color(str, Enum):
    auto = "auto"
    always = "always"
    never = "never"


def color_option() -> Any:
    return typer.Option(
        Color.auto,
        "--color",
        metavar=choices(Color),
        help="Style the output for a terminal (colors, tables): auto (when standard output "
        "is a terminal and NO_COLOR is not set), always (also into a pipe) or never.",
        show_default=True,
    )


def use_color(choice: Color) -> bool:
    """Whether to style the output: `--color`, else NO_COLOR and whether stdout is a tty."""
    if choice is not Color.auto:
        return choice is Color.always
    if os.environ.get("NO_COLOR"):
        return False
    return sys.stdout.isatty()


def quiet_option() -> Any:
    return typer.Option(
        False,
        "--quiet",
        "-q",
        help="Only the summary (and errors): no line per behavior, no output of the mission "
        "script's own print().",
    )


def debug_option() -> Any:
    return typer.Option(False, "--debug", help="Show the traceback if the mission raises.")


def seed_option() -> Any:
    return typer.Option(
        None,
        "--seed",
        metavar="N",
        help="Seed of the simulator's random failures (default: the project's, else 0).",
        show_default=False,
    )


def timeout_option(help: str) -> Any:
    """`--timeout SECONDS`: the wall-clock limit of the user's code (no default: a real
    flight or a corpus replay has no natural bound, and a signal now always ends a run;
    `--max-sim-time` already ends a mission that keeps the simulated clock going). No
    `min=`: that would make typer read it with pydantic, a third of `verify`'s start-up;
    `apply_timeout` checks it."""
    return typer.Option(None, "--timeout", metavar="SECONDS", help=help, show_default=False)


def apply_timeout(seconds: float | None) -> None:
    """The limit `--timeout` sets on each run of the user's code in this command."""
    if seconds is not None and not seconds >= 0:  # (NaN too)
        raise AeroexecError(f"invalid value for --timeout: {seconds:g}: give 0 or more seconds")
    limit_user_code(seconds)


def jobs_option(help: str) -> Any:
    return typer.Option(1, "--jobs", "-j", metavar="N", min=1, help=help, show_default=True)


def connect_option(default: str | None, help: str) -> Any:
    return typer.Option(
        default, "--connect", metavar="URL", help=help, show_default=default is not None
    )


def allow_remote_option(help: str) -> Any:
    return typer.Option(False, "--allow-remote", help=help)
