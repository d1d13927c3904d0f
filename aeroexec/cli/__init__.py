"""The `aeroexec` command line (typer). Each command lives in its own module, imported
when the command is used (the table is `commands.py`, the loading `app.LazyGroup`)."""

from __future__ import annotations

import os

from aeroexec.cli.app import app

#: numpy's OpenBLAS starts a thread per core when numpy is imported, and they spin a while
#: before they sleep: 0.11 s of CPU in a 2-core machine's `aeroexec run --spec` (0.65 s in
#: all, measured), for matrix routines aeroexec never calls. One, unless the user says.
BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "1")


def main() -> None:
    os.environ.setdefault(*BLAS_THREADS)  # before any command imports numpy
    # `python -m aeroexec` too says `aeroexec run: error: ...`, not `python -m aeroexec run`.
    app(prog_name="aeroexec")


__all__ = ["app", "main"]
