"""How every aeroexec command shows itself and reads a wrong command line.

typer builds each command from its function; these classes change only its face, to the
vocabulary of docs/cli.md:

* the usage line and the parameter list name every value by its metavar (`MISSION`,
  `-o, --output FILE`, `-f, --format [text|json]`), never by a Python type (`<path>`);
* a wrong command line (an unknown option, a missing argument, a bad value) is one line on
  stderr, `aeroexec CMD: error: ...`, and exit code 2, like every other aeroexec error;
* a group called bare (`aeroexec`, `aeroexec catalog`) prints its help and exits 0;
* a value is read without pydantic when it is plain (`PlainValues`): start-up time.

typer (since 0.26) carries its own copy of click as `typer._click`; this module and
`app.py` are the only places that reach into it (pyproject.toml pins typer's minor
version for that reason).
"""

from __future__ import annotations

import re
import sys
from collections.abc import Callable, Sequence
from contextvars import ContextVar
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import Any, get_args, get_origin

import typer
import typer.core
from typer._click import exceptions as click_errors
from typer._click.core import Context, Parameter
from typer._click.formatting import HelpFormatter
from typer._coercion import RuntimeParam, build_runtime_param
from typer._param_types import coerce_cli_choice, coerce_cli_path

#: The command running now (`aeroexec run`), for the one line an error becomes.
_RUNNING: ContextVar[str] = ContextVar("aeroexec_command", default="aeroexec")

#: Options a command dropped, with what to use instead (`import -m` was its mapping
#: before `-m` meant --mission everywhere).
REMOVED_OPTIONS: dict[str, dict[str, str]] = {
    "aeroexec import": {"-m": "--mapping (-m means --mission in every command)"},
}


#: A hyphen inside a word (`--on-exit`, `non-loopback`): help is never wrapped there.
_INNER_HYPHEN = re.compile(r"(?<=\w)-(?=\w)")
_KEPT = "\u2011"  # a non-breaking hyphen, for the wrapping only


class Formatter(HelpFormatter):
    """click's help formatter, wrapping lines at spaces only."""

    def write_text(self, text: str) -> None:
        super().write_text(_INNER_HYPHEN.sub(_KEPT, text))

    def write_dl(self, rows: Sequence[tuple[str, str]], *args: Any, **kwargs: Any) -> None:
        kept = [(first, _INNER_HYPHEN.sub(_KEPT, second)) for first, second in rows]
        super().write_dl(kept, *args, **kwargs)

    def getvalue(self) -> str:
        return super().getvalue().replace(_KEPT, "-")


class AeroContext(typer.Context):
    formatter_class = Formatter


def running() -> str:
    """`aeroexec CMD`: who says the error line (`aeroexec` outside a command)."""
    return _RUNNING.get()


def is_argument(param: Parameter) -> bool:
    return param.param_type_name == "argument"


def usage_name(param: Parameter) -> str:
    """How the usage line shows an argument: `MISSION`, `[REC2]`, `REC...`, `[CATALOG...]`."""
    name = param.metavar or (param.name or "").upper()
    return name if param.required else f"[{name}]"


def option_names(param: Parameter) -> str:
    """`-o, --output FILE` (short name first), or `--spawn / --no-spawn` for a flag pair."""
    names = sorted(param.opts, key=len)
    text = ", ".join(names)
    if param.secondary_opts:
        text += " / " + ", ".join(sorted(param.secondary_opts, key=len))
    if not getattr(param, "is_flag", False) and param.metavar:
        text += f" {param.metavar}"
    return text


def shown_default(param: Parameter) -> str | None:
    """The default the help shows after the text (`[default: text]`), or None."""
    if not getattr(param, "show_default", False) or getattr(param, "is_flag", False):
        return None
    default = param.default
    if default is None or default is False or default in ((), []) or callable(default):
        return None
    if isinstance(default, Enum):
        return str(default.value)
    return str(default)


def help_record(param: Parameter) -> tuple[str, str] | None:
    if getattr(param, "hidden", False):
        return None
    text = getattr(param, "help", None) or ""
    extras = []
    default = shown_default(param)
    if default is not None:
        extras.append(f"default: {default}")
    if param.required and not is_argument(param):
        extras.append("required")
    if extras:
        text = f"{text}  [{'; '.join(extras)}]" if text else f"[{'; '.join(extras)}]"
    if is_argument(param):
        return (param.metavar or (param.name or "").upper(), text)
    return (option_names(param), text)


def write_parameters(command: Any, ctx: Context, formatter: HelpFormatter) -> None:
    arguments, options = [], []
    for param in command.get_params(ctx):
        record = help_record(param)
        if record is not None:
            (arguments if is_argument(param) else options).append(record)
    for title, records in (("Arguments", arguments), ("Options", options)):
        if records:
            with formatter.section(title):
                formatter.write_dl(records)


def _hint(param: Parameter | None) -> str:
    if param is None:
        return ""
    if is_argument(param):
        return param.metavar or (param.name or "").upper()
    return max([*param.opts, *param.secondary_opts], key=len, default=param.name or "")


def _sentence(text: str) -> str:
    """Click's messages as aeroexec writes them: lower case first, no final period."""
    text = " ".join(text.split()).rstrip(".")
    return text if text[1:2].isupper() else text[:1].lower() + text[1:]


def usage_message(exc: click_errors.ClickException) -> str:
    """What was wrong with the command line, as the tail of one error line."""
    if isinstance(exc, click_errors.MissingParameter):
        param = exc.param
        kind = "argument" if param is not None and is_argument(param) else "option"
        what = _hint(param)
        if param is not None and not is_argument(param) and param.metavar:
            what += f" {param.metavar}"
        return f"missing {kind} {what}".rstrip()
    if isinstance(exc, click_errors.BadParameter):
        cause = exc.__cause__
        errors = getattr(cause, "errors", None)
        detail = _sentence(exc.message)
        if callable(errors):
            first = (errors() or [{}])[0]
            if "input" in first:
                # pydantic's wording, less its "Value error, " prefix.
                said = _sentence(str(first.get("msg", detail)).removeprefix("Value error, "))
                given = repr(first["input"])
                detail = said if given in said else f"{given}: {said}"
        return f"invalid value for {_hint(exc.param)}: {detail}"
    if isinstance(exc, click_errors.NoSuchOption):
        ctx = exc.ctx
        path = ctx.command_path if ctx is not None else ""
        instead = REMOVED_OPTIONS.get(path, {}).get(exc.option_name)
        text = f"no such option {exc.option_name}"
        if instead is not None:
            return f"{text}; use {instead}"
        if exc.possibilities:
            return f"{text} (did you mean {' or '.join(sorted(exc.possibilities))}?)"
        return text
    text = _sentence(exc.format_message())
    text, _, suggestion = text.partition(". Did you mean ")
    return f"{text} (did you mean {suggestion})" if suggestion else text


def usage_error_line(exc: click_errors.ClickException) -> str:
    """`aeroexec run: error: missing argument MISSION (aeroexec run -h for help)`."""
    ctx = getattr(exc, "ctx", None)
    who = ctx.command_path if ctx is not None else running()
    hint = f" ({who} -h for help)" if isinstance(exc, click_errors.UsageError) else ""
    return f"{who}: error: {usage_message(exc)}{hint}"


def _parse(parse: Any, ctx: Context, args: list[str]) -> list[str]:
    """click's parser raises some errors (an option without its value) without saying
    whose command line it was reading: tell them, so the line names the command.
    Every parameter (the help option and typer's completion options too) is known by
    now: each plain one gets its pydantic-free reading here."""
    read_plain_values(ctx.command.get_params(ctx))
    try:
        return parse(ctx, args)  # type: ignore[no-any-return]
    except click_errors.UsageError as exc:
        if exc.ctx is None:
            exc.ctx, exc.cmd = ctx, ctx.command
        raise


#: A plain number as typed, which Python reads as pydantic does (anything else, `1_000`,
#: ` 5`, `1e3`, `inf`, is left to pydantic).
_PLAIN_INT = re.compile(r"-?[0-9]+")
_PLAIN_FLOAT = re.compile(r"-?[0-9]+(\.[0-9]+)?")

#: Reads one item of a parameter's type, or raises `_NotPlain` to leave it to typer.
Reader = Callable[[Any, Parameter, Context], Any]


class _NotPlain(Exception):
    """A value (or type) the plain readers leave to typer's own coercion."""


def _read_str(value: Any, param: Parameter, ctx: Context) -> str:
    if type(value) is str:
        return value
    raise _NotPlain


def _read_bool(value: Any, param: Parameter, ctx: Context) -> bool:
    if type(value) is bool:
        return value
    raise _NotPlain


def _read_int(value: Any, param: Parameter, ctx: Context) -> int:
    if type(value) is int:
        return value
    if type(value) is str and _PLAIN_INT.fullmatch(value):
        return int(value)
    raise _NotPlain


def _read_float(value: Any, param: Parameter, ctx: Context) -> float:
    if type(value) is float:
        return value
    if type(value) is int or (type(value) is str and _PLAIN_FLOAT.fullmatch(value)):
        return float(value)
    raise _NotPlain


def _path_reader(param_info: Any) -> Reader:
    def read(value: Any, param: Parameter, ctx: Context) -> Any:
        if type(value) is str and value:
            # A Path already: typer's checks (exists, file_okay...) without its pydantic
            # str -> Path step, which makes the same Path.
            return coerce_cli_path(Path(value), param_info, path_type=Path, param=param, ctx=ctx)  # type: ignore[arg-type]
        raise _NotPlain

    return read


def _choice_reader(choices: Sequence[Any], case_sensitive: bool) -> Reader:
    def read(value: Any, param: Parameter, ctx: Context) -> Any:
        return coerce_cli_choice(value, choices=choices, case_sensitive=case_sensitive, ctx=ctx)

    return read


_READERS: dict[Any, Reader] = {str: _read_str, bool: _read_bool, int: _read_int, float: _read_float}


def _reader(annotation: Any, param_info: Any) -> Reader | None:
    """How to read one item of `annotation` without pydantic, or None (typer's way)."""
    if annotation in _READERS:
        return _READERS[annotation]
    if annotation is Path:
        return _path_reader(param_info)
    if isinstance(annotation, type) and issubclass(annotation, Enum):
        return _choice_reader(list(annotation), param_info.case_sensitive)
    return None


@dataclass(frozen=True)
class PlainValues(RuntimeParam):
    """Reads a parameter of a plain type (str, bool, int, float, Path, an Enum, or a
    list of one of them) as typer's pydantic adapters would, without importing pydantic
    (its import is a third of `aeroexec verify`'s start-up).

    Only what is certain to come out the same is read here: a value of the exact type,
    a plain number, a non-empty path, a choice. Anything else, and every value that
    fails (so every error message), goes to typer's own coercion."""

    read: Reader
    many: bool

    def _coerce_value(self, value: Any, param: Any, ctx: Context) -> Any:
        try:
            if not self.many:
                return self.read(value, param, ctx)
            items = value if isinstance(value, (list, tuple)) else [value]
            return [self.read(item, param, ctx) for item in items]
        except Exception:
            typer_own = build_runtime_param(param.type_descriptor)
            return typer_own._coerce_value(value, param=param, ctx=ctx)

    @classmethod
    def of(cls, param: Any) -> PlainValues | None:
        """The plain reading of a typer parameter, or None when its type is not plain."""
        descriptor = getattr(param, "type_descriptor", None)
        if descriptor is None or descriptor.is_file:
            return None
        info = descriptor.parameter_info
        if info.parser is not None:
            return None
        if info.min is not None or info.max is not None or info.path_type is not None:
            return None
        annotation = descriptor.annotation
        many = get_origin(annotation) is list
        item = get_args(annotation)[0] if many else annotation
        read = _reader(item, info)
        if read is None:
            return None
        return cls(parameter_info=info, annotation=annotation, read=read, many=many)


def read_plain_values(params: Sequence[Parameter]) -> None:
    """Give each plain parameter its pydantic-free reading, in the `_runtime_param` typer
    caches (typer builds its own, for the others, when first needed)."""
    for param in params:
        if getattr(param, "_runtime_param", True) is None:
            plain = PlainValues.of(param)
            if plain is not None:
                param._runtime_param = plain  # type: ignore[attr-defined]


class Command(typer.core.TyperCommand):
    """One aeroexec command (every `@app.command` is one)."""

    context_class = AeroContext

    def parse_args(self, ctx: Context, args: list[str]) -> list[str]:
        return _parse(super().parse_args, ctx, args)

    def collect_usage_pieces(self, ctx: Context) -> list[str]:
        pieces = [self.options_metavar] if self.options_metavar else []
        return pieces + [usage_name(p) for p in self.get_params(ctx) if is_argument(p)]

    def format_options(self, ctx: Context, formatter: HelpFormatter) -> None:
        write_parameters(self, ctx, formatter)

    def invoke(self, ctx: Context) -> Any:
        token = _RUNNING.set(ctx.command_path)
        try:
            return super().invoke(ctx)
        finally:
            _RUNNING.reset(token)


class Group(typer.core.TyperGroup):
    """A command with subcommands (`aeroexec`, `aeroexec catalog`, `aeroexec report`)."""

    context_class = AeroContext

    def collect_usage_pieces(self, ctx: Context) -> list[str]:
        pieces = [self.options_metavar] if self.options_metavar else []
        return [*pieces, self.subcommand_metavar]

    def format_options(self, ctx: Context, formatter: HelpFormatter) -> None:
        write_parameters(self, ctx, formatter)
        self.format_commands(ctx, formatter)

    def parse_args(self, ctx: Context, args: list[str]) -> list[str]:
        # Bare `aeroexec` (or `aeroexec catalog`) asks what there is: the help, exit 0.
        if not args and self.no_args_is_help and not ctx.resilient_parsing:
            typer.echo(ctx.get_help(), color=ctx.color)
            ctx.exit(0)
        return _parse(super().parse_args, ctx, args)

    def main(
        self,
        args: Sequence[str] | None = None,
        prog_name: str | None = None,
        complete_var: str | None = None,
        standalone_mode: bool = True,
        **extra: Any,
    ) -> Any:
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode, **extra)
        try:
            result = super().main(args, prog_name, complete_var, False, **extra)
        except click_errors.ClickException as exc:
            typer.echo(usage_error_line(exc), err=True)
            sys.exit(exc.exit_code)
        except typer.Abort:
            typer.echo(f"{running()}: aborted", err=True)
            sys.exit(1)
        # Not standalone, click returns the exit code of a typer.Exit (commands return None).
        sys.exit(result if isinstance(result, int) else 0)


class Typer(typer.Typer):
    """`typer.Typer` whose commands and groups are the classes above."""

    def __init__(self, **settings: Any) -> None:
        settings.setdefault("cls", Group)
        super().__init__(**settings)

    def command(self, name: str | None = None, **settings: Any) -> Any:
        settings.setdefault("cls", Command)
        return super().command(name, **settings)
