"""`aeroexec report merge SHARD.json...`: the shards of a sharded replay, as one report."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Annotated

import typer

from aeroexec.cli.app import app, error_line, guarded
from aeroexec.cli.command import Typer
from aeroexec.cli.options import output_option
from aeroexec.cli.replay_cmd import OutputFormat, report_format_option
from aeroexec.cli.spec import (
    verdicts_failed,
    verdicts_text,
    with_verdicts_json,
    with_verdicts_junit,
)
from aeroexec.errors import Mark, ReportError
from aeroexec.replay.merge import merge_shards, read_shard
from aeroexec.replay.report import replay_json, replay_junit, replay_text

report_app = Typer(
    help=(
        "Work with replay reports: merge the shards of a CI matrix into one.\n\n"
        "\b\n"
        "Example:\n"
        "  aeroexec report merge shard-*.json --check -f junit -o replay.xml"
    ),
    no_args_is_help=True,
    rich_markup_mode=None,
)
app.add_typer(report_app, name="report")


def _write(path: str, text: str) -> None:
    """All of `text` at `path`, or nothing there (a temporary file renamed into place)."""
    target = Path(path)
    try:
        descriptor, temporary = tempfile.mkstemp(
            prefix=f".{target.name}.", dir=target.parent if str(target.parent) else "."
        )
    except OSError as exc:
        raise ReportError(f"cannot write: {exc.strerror or exc}", Mark(path)) from None
    try:
        with os.fdopen(descriptor, "w", encoding="utf-8") as stream:
            stream.write(text)
        os.replace(temporary, target)
    except OSError as exc:
        Path(temporary).unlink(missing_ok=True)
        raise ReportError(f"cannot write: {exc.strerror or exc}", Mark(path)) from None
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


@report_app.command("merge")
@guarded
def merge(
    shards: Annotated[
        list[str],
        typer.Argument(
            metavar="REPORT...",
            help="The JSON reports of every shard (`aeroexec replay --shard K/N --format json`).",
            show_default=False,
        ),
    ],
    output_format: OutputFormat = report_format_option(),
    output: str | None = output_option("Write the report here (default: standard output)."),
    check: Annotated[
        bool,
        typer.Option(
            "--check",
            help="Exit 1 when any replay differs from its recording (or, replayed with "
            "--spec, violates a property).",
        ),
    ] = False,
) -> None:
    """Merge the JSON reports of a sharded replay into the report the unsharded replay
    gives: the same recordings in the same order, the same text, JSON or JUnit, the same
    exit code. Refuses (exit 2) shards that do not make one whole run: one missing or
    given twice, or shards of different corpora, catalogs or shard counts.

    \b
    Example:
      aeroexec report merge shard-*.json --check --format junit -o replay.xml

    Exit codes: 0 merged (with --check: no differences); 1 with --check, some replay
    differs or violates a property (shards replayed with --spec); 2 a recording could
    not be read, or the shards could not be merged.
    """
    results = merge_shards([read_shard(path) for path in shards])
    # Shards replayed with --spec carry each replay's property verdicts: rendered as
    # `replay --spec` renders them.
    checked = [r.properties for r in results if r.properties is not None]
    if output_format is OutputFormat.json:
        text = replay_json(results)
        text = with_verdicts_json(text, checked) if checked else text
    elif output_format is OutputFormat.junit:
        text = replay_junit(results)
        text = with_verdicts_junit(text, checked) if checked else text
    else:
        text = replay_text(results)
        if checked:
            text = (text + "\n" if text else "") + verdicts_text(checked).rstrip("\n")
    if output is not None:
        _write(output, text + "\n")
    elif text:
        typer.echo(text)
    for result in results:
        if result.error is not None:
            error_line(f"{result.recording}: error: {result.error}")
    if any(r.error is not None for r in results):
        raise typer.Exit(2)
    if check and (verdicts_failed(checked) or not all(r.equal for r in results)):
        raise typer.Exit(1)
