"""The `aeroexec` command line (typer). Each command lives in its own module, imported
when the command is used (the table is `commands.py`, the loading `app.LazyGroup`)."""

from __future__ import annotations

from aeroexec.cli.app import app


def main() -> None:
    # `python -m aeroexec` too says `aeroexec run: error: ...`, not `python -m aeroexec run`.
    app(prog_name="aeroexec")


__all__ = ["app", "main"]
