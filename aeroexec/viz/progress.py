"""A progress bar for long conversions: rich on a terminal, nothing otherwise."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TextIO

#: A bar is shown only for recordings with at least this many messages.
MIN_MESSAGES = 20_000

Advance = Callable[[int], None]


def _ignore(_: int) -> None:
    return None


@contextmanager
def progress_bar(
    description: str,
    total: int,
    *,
    stream: TextIO | None = None,
    enabled: bool | None = None,
) -> Iterator[Advance]:
    """Yields `advance(n)`. The bar goes to `stream` (stderr) and only when it is a
    terminal (or `enabled` says so) and `total` is large enough to be worth one."""
    out = stream if stream is not None else sys.stderr
    if enabled is None:
        enabled = out.isatty() and total >= MIN_MESSAGES
    if not enabled:
        yield _ignore
        return
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeRemainingColumn

    columns = (
        "{task.description}",
        BarColumn(),
        MofNCompleteColumn(),
        TimeRemainingColumn(),
    )
    with Progress(*columns, console=Console(file=out), transient=True) as progress:
        task = progress.add_task(description, total=total)

        def advance(n: int) -> None:
            progress.advance(task, n)

        yield advance
