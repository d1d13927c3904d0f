"""Waiting for worker processes without losing a signal sent to the parent.

`replay --jobs N` waits for its workers in the parent. A SIGTERM sent to the parent alone
(`kill PID`, a CI runner's timeout) is only noted by its handler (`aeroexec.interrupts`),
so a parent blocked in `future.result()` would wait for every replay to finish and then
forget the signal. `completed_or_interrupted` waits in short slices and checks for a
signal between them; on one it cancels what has not started, passes the signal on to the
workers (which stop at their next safe point and finalize their recordings) and waits for
them, then raises the parent's `Interrupted` with what the workers said about their
outputs.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from typing import Any

from aeroexec.interrupts import Interrupted
from aeroexec.interrupts import check as check_interrupts

#: How long the parent waits before looking for a signal again (s).
POLL_S = 0.2


def completed_or_interrupted(
    pool: ProcessPoolExecutor, futures: Sequence[Future[Any]]
) -> Iterator[Future[Any]]:
    """Each future as it completes; `Interrupted` (after the workers stopped) on a signal."""
    pending = set(futures)
    while pending:
        try:
            check_interrupts()
            done, pending = wait(pending, timeout=POLL_S, return_when=FIRST_COMPLETED)
        except Interrupted as stop:
            _stop_workers(pool, futures, stop)
            raise
        yield from [f for f in futures if f in done]  # in input order


def _stop_workers(
    pool: ProcessPoolExecutor, futures: Sequence[Future[Any]], stop: Interrupted
) -> None:
    for future in futures:
        future.cancel()  # not started yet: never will be
    # The workers note the signal (`interrupts.in_worker_process`) and stop at their next
    # safe point, finalizing their recordings. `_processes` is the executor's own table
    # of worker processes (pid -> Process); there is no public one.
    for pid in list(getattr(pool, "_processes", {}) or {}):
        with contextlib.suppress(OSError):
            os.kill(pid, stop.signum)
    wait(futures)
    for future in futures:
        if future.cancelled():
            continue
        error = future.exception()
        if isinstance(error, Interrupted):
            stop.notes.extend(error.notes)
    pool.shutdown(wait=True, cancel_futures=True)
