"""The typer application object and the helpers every command shares.

Commands live in their own modules (`cli/<name>_cmd.py`) and register on `app`; they
stay thin: parse, call the library, format, set the exit code. `app` imports a command's
module only when that command is used (`LazyGroup`, with the table in `commands.py`), so
`aeroexec --version` does not pay for the verifier, the bag reader or the MAVLink dialect.
"""

from __future__ import annotations

import functools
import importlib
import sys
from collections.abc import Callable, Iterator, Mapping, MutableMapping
from typing import Any, TypeVar

import typer
import typer.core
import typer.main
from typer._click.core import Command as ClickCommand
from typer._click.shell_completion import CompletionItem

from aeroexec import __version__
from aeroexec.cli.command import Group, Typer, running
from aeroexec.cli.commands import COMMANDS
from aeroexec.errors import AeroexecError, OutputLost, one_line
from aeroexec.interrupts import Interrupted, TimedOut, signals_as_interrupts, user_place
from aeroexec.interrupts import check as check_interrupts


class _LazyCommands(MutableMapping[str, Any]):
    """The group's commands: every name of `COMMANDS` from the start, each built (its
    module imported) the first time it is looked up."""

    def __init__(self, built: Mapping[str, Any], load: Callable[[str], Any]) -> None:
        self._built: dict[str, Any] = dict(built)
        self._load = load

    def __getitem__(self, name: str) -> Any:
        command = self._built.get(name)
        if command is None:
            command = self._load(name) if name in COMMANDS else None
            if command is None:
                raise KeyError(name)
            self._built[name] = command
        return command

    def __setitem__(self, name: str, command: Any) -> None:
        self._built[name] = command

    def __delitem__(self, name: str) -> None:
        del self._built[name]

    def __iter__(self) -> Iterator[str]:
        yield from COMMANDS
        yield from (name for name in self._built if name not in COMMANDS)

    def __len__(self) -> int:
        return len(COMMANDS) + sum(1 for name in self._built if name not in COMMANDS)

    def __contains__(self, name: object) -> bool:
        return name in COMMANDS or name in self._built

    def built(self, name: str) -> Any | None:
        return self._built.get(name)


def _load_command(name: str) -> Any | None:
    """Import the module of command `name` (it registers on `app`) and build it."""
    importlib.import_module(f"aeroexec.cli.{COMMANDS[name].module}")
    for info in app.registered_commands:
        callback_name = info.callback.__name__ if info.callback else ""
        if (info.name or typer.main.get_command_name(callback_name)) == name:
            return typer.main.get_command_from_info(
                info,
                pretty_exceptions_short=app.pretty_exceptions_short,
                rich_markup_mode=app.rich_markup_mode,
            )
    for group_info in app.registered_groups:
        if group_info.name == name:
            return typer.main.get_group_from_info(
                group_info,
                pretty_exceptions_short=app.pretty_exceptions_short,
                rich_markup_mode=app.rich_markup_mode,
                suggest_commands=app.suggest_commands,
            )
    return None


class LazyGroup(Group):
    """The root group: commands load on first use; `--help` and shell completion list
    them from the table."""

    def __init__(self, *, commands: Mapping[str, Any] | None = None, **attrs: Any) -> None:
        super().__init__(**attrs)
        self.commands = _LazyCommands(commands or {}, _load_command)

    def list_commands(self, ctx: Any) -> list[str]:
        return list(self.commands)

    def format_commands(self, ctx: Any, formatter: Any) -> None:
        commands = self.commands
        assert isinstance(commands, _LazyCommands)
        names = list(commands)
        limit = formatter.width - 6 - max(len(name) for name in names)
        rows = []
        for name in names:
            command = commands.built(name)
            if command is None:  # not loaded: its summary, shortened as click would
                command = typer.core.TyperCommand(name=name, help=COMMANDS[name].summary)
            if not command.hidden:
                rows.append((name, command.get_short_help_str(limit)))
        if rows:
            with formatter.section("Commands"):
                formatter.write_dl(rows)

    def shell_complete(self, ctx: Any, incomplete: str) -> list[CompletionItem]:
        # Completing a command name must not import every command (rerun, the verifier...).
        names = [
            CompletionItem(name, help=entry.summary)
            for name, entry in COMMANDS.items()
            if name.startswith(incomplete)
        ]
        # The group's own options, but not typer's command listing (it builds them all).
        return names + ClickCommand.shell_complete(self, ctx, incomplete)


app = Typer(
    cls=LazyGroup,
    name="aeroexec",
    help=(
        "Behavior management for a drone's executive layer (after the 2017 Aerostack "
        "design): run missions on a deterministic core, record them to MCAP, verify "
        "catalogs, replay and diff recordings, fly over MAVLink, view in Rerun.\n\n"
        "Start with `aeroexec run missions/appendix_c.py -o flight.mcap`; every command "
        "has -h.\n\n"
        "Exit codes: 0 success, 1 the check found problems (or the mission failed), "
        "2 an input could not be read or the command line is wrong, 128+N stopped by "
        "signal N."
    ),
    no_args_is_help=True,
    context_settings={"help_option_names": ["-h", "--help"]},
    add_completion=True,
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


def say(kind: str, message: str) -> None:
    """`aeroexec CMD: KIND: message` on stderr (kind: error, warning, note)."""
    error_line(f"{running()}: {kind}: {message}")


def guarded(func: F) -> F:
    """Turn aeroexec's input errors (and outputs it could not write) into one stderr
    line and exit code 2 (no traceback), and SIGINT/SIGTERM/SIGHUP into a clean stop:
    the command's `finally` blocks finish or remove its output, then one line and exit
    code 128 + signal."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            with signals_as_interrupts(who=running()):
                result = func(*args, **kwargs)
                # A signal that came after the last safe point still stops with 128+N
                # (the command's outputs are complete by now).
                check_interrupts()
                return result
        except Interrupted as exc:
            error_line(f"{running()}: {exc.line()}")
            raise typer.Exit(exc.exit_code) from None
        except (AeroexecError, OutputLost) as caught:
            exc = caught.error if isinstance(caught, OutputLost) else caught
            text = str(exc)
            if exc.mark is None:
                text = f"{running()}: error: {text}"
            error_line(text)
            raise typer.Exit(2) from None
        except TimedOut as exc:
            # What a command did not turn into a mission's failure: still one line.
            error_line(f"{running()}: error: {exc}")
            raise typer.Exit(1) from None
        except SystemExit as exc:
            # The user's code called sys.exit() where no command expected it: aeroexec
            # decides its own exit code (0, 1, 2 or 128+N), so this is an error.
            where = _exit_place(exc)
            error_line(
                f"{where or running()}: error: the user's code called sys.exit({exc.code!r})"
            )
            raise typer.Exit(2) from None
        except BrokenPipeError:
            # `aeroexec ... | head` closed the pipe: not an error worth a traceback.
            sys.stderr.close()
            raise typer.Exit(0) from None
        except OSError as exc:
            # A path the system refused where no reader of aeroexec.inputs stood guard (a
            # parent directory without search permission, met by a `Path.exists()`):
            # still one line naming the file, never a traceback.
            if exc.filename is None:
                raise
            error_line(one_line(f"{exc.filename}: error: {exc.strerror or exc}"))
            raise typer.Exit(2) from None

    return wrapper  # type: ignore[return-value]


def _exit_place(exc: BaseException) -> str:
    """`file:line` of the innermost user frame `exc` passed through ('' if none)."""
    tb = exc.__traceback__
    while tb is not None and tb.tb_next is not None:
        tb = tb.tb_next
    return user_place(tb.tb_frame) if tb is not None else ""
