"""The `aeroexec` command line (typer). Each command lives in its own module, imported
when the command is used (the table is `commands.py`, the loading `app.LazyGroup`)."""

from __future__ import annotations

from aeroexec.cli.app import app


def main() -> None:
    app()


__all__ = ["app", "main"]
