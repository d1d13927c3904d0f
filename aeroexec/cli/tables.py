"""Tables for terminal output: rich when styled (`--color`), plain aligned text otherwise.

Plain text keeps output stable for pipes, logs and tests.
"""

from __future__ import annotations

import typer


def print_table(title: str, headers: list[str], rows: list[list[str]], styled: bool) -> None:
    if styled:
        from rich.console import Console
        from rich.table import Table

        table = Table(title=title)
        for header in headers:
            table.add_column(header)
        for row in rows:
            table.add_row(*row)
        # force_terminal: `--color always` styles a pipe too.
        Console(force_terminal=True).print(table)
        return
    widths = [
        max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(headers)
    ]
    typer.echo(title)
    typer.echo("  ".join(h.ljust(w) for h, w in zip(headers, widths, strict=True)).rstrip())
    for row in rows:
        typer.echo("  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip())
