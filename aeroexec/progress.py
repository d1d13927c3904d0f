"""Progress of long work: the library reports it through a `ProgressFactory` it is given
(import, view, a single replay), and the command line draws it as a rich bar on a
terminal (nothing otherwise). The library never draws: a caller that passes no factory
gets no progress, and tests pass one that only counts."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager
from typing import Literal, TextIO

#: A bar is shown only for work of at least this many messages.
MIN_MESSAGES = 20_000

#: `advance(n)`: n more units of the work are done.
Advance = Callable[[int], None]
#: `progress(description, total)` -> a context manager yielding `advance`.
ProgressFactory = Callable[[str, int], AbstractContextManager[Advance]]
#: How a bar shows its count: `n/total`, bytes (`1.2/8.4 MB`) or a percentage.
Unit = Literal["count", "bytes", "percent"]


def _ignore(_: int) -> None:
    return None


@contextmanager
def progress_bar(
    description: str,
    total: int,
    *,
    stream: TextIO | None = None,
    enabled: bool | None = None,
    unit: Unit = "count",
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
    from rich.progress import (
        BarColumn,
        DownloadColumn,
        MofNCompleteColumn,
        Progress,
        TaskProgressColumn,
        TimeRemainingColumn,
    )

    count = {"count": MofNCompleteColumn, "bytes": DownloadColumn}.get(unit, TaskProgressColumn)
    columns = ("{task.description}", BarColumn(), count(), TimeRemainingColumn())
    with Progress(*columns, console=Console(file=out), transient=True) as progress:
        task = progress.add_task(description, total=total)

        def advance(n: int) -> None:
            progress.advance(task, n)

        yield advance
