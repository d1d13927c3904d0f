"""`--spec FILE`: properties for `check`, `run`, `fly` and `replay --check`.

The properties package (RTAMT and its ANTLR runtime) is imported only when a command is
given --spec (or is `check`): `aeroexec run` without it starts as fast as before.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated

import typer

if TYPE_CHECKING:
    from aeroexec.properties.check import Verdict
    from aeroexec.properties.monitor import PropertyMonitor

SpecOption = Annotated[
    list[str] | None,
    typer.Option(
        "--spec",
        metavar="FILE",
        help="A property file, or aeroexec:safety (repeatable); docs/properties.md.",
        show_default=False,
    ),
]


def monitor_for(spec: list[str] | None) -> PropertyMonitor | None:
    """A monitor of the properties of `spec` (None without --spec); `PropertyError`
    (one line, exit 2) for a bad property file, before anything runs."""
    if not spec:
        return None
    from aeroexec.properties.monitor import PropertyMonitor
    from aeroexec.properties.spec import load_properties

    return PropertyMonitor(load_properties(spec))


def print_verdicts(verdicts: list[Verdict], source: str) -> bool:
    """One line per violated (or unchecked) property, then a summary; True when a
    property of severity error was violated."""
    from aeroexec.properties.check import CheckReport
    from aeroexec.properties.report import text

    report = CheckReport(source, tuple(verdicts), 0.0)
    typer.echo(text([report]).replace("1 recording(s), ", "properties: "), nl=False)
    return report.failed
