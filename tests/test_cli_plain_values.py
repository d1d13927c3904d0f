"""The command line reads plain values without pydantic (start-up time, issue 17), and
reads them exactly as typer's own coercion does: same values, same types, same errors."""

from __future__ import annotations

from enum import Enum
from pathlib import Path
from typing import Any, get_args, get_origin

import pytest
import typer.main
from typer._click import exceptions as click_errors
from typer._click.core import Context
from typer._coercion import build_runtime_param

from aeroexec.cli import app
from aeroexec.cli.command import PlainValues, usage_message
from aeroexec.cli.commands import COMMANDS

ROOT = Path(__file__).resolve().parent.parent

#: Values a user (or a default) gives, the plain ones and those left to typer.
SAMPLES: dict[Any, list[Any]] = {
    str: ["abc", "", "-", "ünï", 5],
    bool: [True, False, "true", "no", ""],
    int: ["5", "007", "-3", "+4", " 5", "1_000", "1.0", "x", "", 5, 2.0, True],
    float: ["1.5", "-2", "007.5", "1e3", "inf", ".5", "5.", "x", "", 1, 2.5, True],
    Path: ["catalog/default.yaml", "catalog", "", "-", "no/such/file", Path("missions")],
}


def _samples(item: Any) -> list[Any]:
    if isinstance(item, type) and issubclass(item, Enum):
        values = [str(member.value) for member in item]
        return [*values, *(v.upper() for v in values), "no-such-choice", next(iter(item)), 3]
    return SAMPLES[item]


def _plain_params() -> list[tuple[str, Any, Any, Any]]:
    group = typer.main.get_command(app)
    found = []
    commands = [("aeroexec", group)]
    for name in COMMANDS:
        command = group.commands[name]  # type: ignore[attr-defined]
        parts = getattr(command, "commands", {})
        commands += [(f"{name} {sub}", part) for sub, part in parts.items()] or [(name, command)]
    for path, command in commands:
        ctx = Context(command)
        for param in command.get_params(ctx):
            plain = PlainValues.of(param)
            if plain is not None:
                found.append((f"{path} {param.name}", command, param, plain))
    return found


def _outcome(coerce: Any, value: Any, param: Any, ctx: Context) -> tuple[Any, ...]:
    try:
        result = coerce(value, param=param, ctx=ctx)
    except click_errors.BadParameter as exc:
        return ("error", usage_message(exc))
    except Exception as exc:  # the same failure, whatever it is
        return ("raised", type(exc), str(exc))
    if isinstance(result, list):
        return ("list", [(type(item), item) for item in result])
    return ("value", type(result), result)


def test_every_plain_type_of_every_command_is_read_without_pydantic() -> None:
    params = _plain_params()
    kinds = {
        get_args(p.type_descriptor.annotation)[0]
        if get_origin(p.type_descriptor.annotation) is list
        else p.type_descriptor.annotation
        for _, _, p, _ in params
    }
    assert {str, bool, int, float, Path} <= kinds
    assert any(isinstance(k, type) and issubclass(k, Enum) for k in kinds)
    assert any(get_origin(p.type_descriptor.annotation) is list for _, _, p, _ in params)
    # A number with bounds is typer's to read (and to word the error): `--port`.
    group = typer.main.get_command(app)
    bounded = [
        param
        for name in COMMANDS
        for command in [group.commands[name]]  # type: ignore[attr-defined]
        for param in getattr(command, "params", [])
        if getattr(param, "max", None) is not None
    ]
    assert bounded and all(PlainValues.of(param) is None for param in bounded)


@pytest.mark.parametrize("where", [entry[0] for entry in _plain_params()])
def test_plain_values_read_as_typer_reads_them(where: str, monkeypatch: Any) -> None:
    monkeypatch.chdir(ROOT)
    name, command, param, plain = next(e for e in _plain_params() if e[0] == where)
    typer_own = build_runtime_param(param.type_descriptor)
    ctx = Context(command)
    annotation = param.type_descriptor.annotation
    many = get_origin(annotation) is list
    samples = _samples(get_args(annotation)[0] if many else annotation)
    values = [(value,) for value in samples] if many else samples
    if many:
        values.append(tuple(samples[:2]))
    for value in values:
        ours = _outcome(plain.coerce, value, param, ctx)
        theirs = _outcome(typer_own.coerce, value, param, ctx)
        assert ours == theirs, (name, value)
