"""Where replays run: in this process, in worker processes on this machine, or on Ray.

    with executor_for("local", jobs=2, tasks=len(paths)) as executor:
        for done in executor.run(tasks):      # as they finish, whatever the order
            ...
    results = replay_many(paths, options, jobs=2)   # the same, in input order

Every executor runs the same `run_task` on the same `ReplayTask`s, so the verdicts do not
depend on where they ran; only the order in which results arrive does, and `replay_many`
puts them back in input order.

Why `--jobs 2` was no faster than `--jobs 1` on 40 short recordings (measured on this
2-core machine, shared with other work): starting the pool costs ~7 ms (fork), a result
pickles to ~240 bytes, a worker's first replay pays ~8 ms of lazy imports, and handing
one recording over cost the driver ~0.7 ms of CPU (~5% of a 15 ms replay). None of that
explains it: each replay used the same CPU time in one worker or two, but took twice as
long on the clock with two, because the second core was busy with other work; when one
core is free, two workers only take turns on it. What the pool does about what it
controls: workers are forked on Linux (spawn and forkserver, the default elsewhere and
from Python 3.14, import aeroexec again in every worker: ~0.5 s each), before any thread
starts (a progress bar's), with the replay stack already imported; never more workers
than CPUs this process may use nor than recordings; recordings go over in batches of up
to 8 when there are many (the driver's CPU per recording falls to ~0.2 ms); and only two
batches per worker are queued at a time, so the driver holds results, not 10,000
futures. `benchmarks/fleet.py` sets the speed-up beside the parallelism the machine has
free when it is measured.
"""

from __future__ import annotations

import contextlib
import ctypes
import multiprocessing
import os
import signal
import sys
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from types import TracebackType
from typing import Any, Protocol

from aeroexec import interrupts
from aeroexec.errors import AeroexecError
from aeroexec.progress import ProgressFactory
from aeroexec.replay.engine import ReplayOptions, ReplayResult, SessionWatch
from aeroexec.replay.tasks import (
    Completed,
    ReplayTask,
    Task,
    batch_size,
    make_tasks,
    run_batch,
)

#: Batches queued per worker: enough that no worker waits for the next, few enough that
#: a corpus of any size holds only a handful of pending futures.
QUEUED_PER_WORKER = 2
#: How long (s) workers get to finalize their recordings after a signal.
STOP_GRACE_S = 10.0
#: How often (s) a waiting driver looks for a signal (Ctrl-C) to act on.
CHECK_INTERVAL_S = 0.2
LOCAL = "local"
#: prctl(2): the signal a process gets when its parent dies.
_PR_SET_PDEATHSIG = 1


class Executor(Protocol):
    """Runs tasks (replays, fuzz chunks) somewhere; a context manager that starts and
    stops its workers."""

    #: What the report and errors call it: "local", "ray", "ray://head:10001".
    name: str
    #: Local paths must be absolute for its workers (they run in another directory).
    needs_absolute_paths: bool

    def __enter__(self) -> Executor: ...

    def __exit__(
        self,
        kind: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None: ...

    def run(self, tasks: Sequence[Task]) -> Iterator[Completed]:
        """Each task's result as soon as it is there (order: whichever finishes first)."""
        ...


def usable_cpus() -> int:
    """CPUs this process may run on (its affinity, e.g. a CI container's share)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


class InlineExecutor:
    """One recording after the other, in this process (`--jobs 1`). `progress`: each
    replay reports how far it is (`replay_recording`), for one big recording's bar.
    `watch`: who watches the replay as it runs (`replay --live`): one replay's session
    only, so such an executor runs one task."""

    name = LOCAL
    needs_absolute_paths = False

    def __init__(
        self, progress: ProgressFactory | None = None, watch: SessionWatch | None = None
    ) -> None:
        self.progress = progress
        self.watch = watch

    def __enter__(self) -> InlineExecutor:
        return self

    def __exit__(self, *exc_info: object) -> None:
        return None

    def run(self, tasks: Sequence[Task]) -> Iterator[Completed]:
        if self.watch is not None:
            if len(tasks) > 1 or not all(isinstance(t, ReplayTask) for t in tasks):
                # The command refuses more first (`replay --live`): this is a bug.
                raise ValueError("a watched replay runs one recording")
            for task in tasks:
                assert isinstance(task, ReplayTask)
                yield Completed(task.index, task.run(self.progress, self.watch))
            return
        for task in tasks:
            yield Completed(task.index, task.run(self.progress))


def _start_method() -> multiprocessing.context.BaseContext:
    """fork on Linux: a worker starts with aeroexec already imported (spawn and
    forkserver import it again in each worker). Elsewhere the platform's default (fork is
    unsafe on macOS)."""
    if sys.platform == "linux":
        return multiprocessing.get_context("fork")
    return multiprocessing.get_context()


def _warm() -> None:
    """Nothing: a first task that makes the pool fork its workers now."""


def _worker_signals(driver: int) -> None:
    """A worker notes SIGINT, SIGTERM and SIGHUP and stops at its next safe point,
    finalizing the recording it writes (`interrupts.in_worker_process`): Ctrl-C reaches
    the whole terminal's process group, and the driver passes on a signal it got alone.
    And it dies with the driver: a driver killed outright (SIGKILL, the OOM killer, a CI
    timeout) cannot stop it, and its siblings keep the task queue open, so it would
    wait for work forever."""
    interrupts.in_worker_process()
    if sys.platform == "linux":
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
        if os.getppid() != driver:  # the driver died before prctl took effect
            os._exit(1)


class ProcessExecutor:
    """`workers` processes on this machine (`--jobs N`)."""

    name = LOCAL
    needs_absolute_paths = False

    def __init__(self, workers: int) -> None:
        if workers < 2:
            raise ValueError("a process pool needs at least 2 workers: use InlineExecutor")
        self.workers = workers
        self._pool: ProcessPoolExecutor | None = None

    def __enter__(self) -> ProcessExecutor:
        # What a replay imports on first use, imported once here rather than in every
        # worker's first task (and before the fork, so workers share its pages).
        import aeroexec.behaviors  # noqa: F401  (lazy: only batches pay for it)

        self._pool = ProcessPoolExecutor(
            self.workers,
            mp_context=_start_method(),
            initializer=_worker_signals,
            initargs=(os.getpid(),),
        )
        # With fork, the pool starts all its workers at the first submit: do it now,
        # before the caller starts any thread (forking a threaded process can deadlock).
        self._pool.submit(_warm).result()
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        pool, self._pool = self._pool, None
        if pool is None:
            return
        if kind is not None and not issubclass(kind, Exception):
            # Interrupted (a signal): replays in progress are abandoned, not awaited (one
            # may be stuck reading a slow store); the workers are ours to stop.
            workers = list((getattr(pool, "_processes", None) or {}).values())
            manager = getattr(pool, "_executor_manager_thread", None)
            pool.shutdown(wait=False, cancel_futures=True)
            for worker in workers:  # (Python 3.14 has pool.terminate_workers() for this)
                worker.terminate()
            for worker in workers:
                worker.join(5)
                if worker.is_alive():
                    worker.kill()
            # The pool's manager thread closes its wake-up pipe when it sees the workers
            # gone; the interpreter's exit hook writes to that pipe unlocked, so exiting
            # while the thread is still closing it prints an EBADF traceback (3.11-3.13).
            if manager is not None:
                manager.join(5)
            return
        pool.shutdown(wait=True, cancel_futures=True)

    def run(self, tasks: Sequence[Task]) -> Iterator[Completed]:
        pool = self._pool
        if pool is None:
            raise RuntimeError("ProcessExecutor.run outside its `with` block")
        size = batch_size(len(tasks), self.workers)
        waiting = iter([list(tasks[i : i + size]) for i in range(0, len(tasks), size)])
        running: dict[Future[list[Any]], list[Task]] = {}
        unfinished: list[Task] = []
        broken: str | None = None

        def submit() -> None:
            nonlocal broken
            batch = next(waiting, None)
            if batch is None:
                return
            if broken is None:
                try:
                    running[pool.submit(run_batch, batch)] = batch
                    return
                except BrokenProcessPool as exc:
                    broken = str(exc) or "a worker process died"
            unfinished.extend(batch)

        for _ in range(self.workers * QUEUED_PER_WORKER):
            submit()
        while running:
            done, _ = wait(running, timeout=CHECK_INTERVAL_S, return_when=FIRST_COMPLETED)
            try:
                interrupts.check()
            except interrupts.Interrupted as stop:
                self._stop_workers(pool, running, stop)
                raise
            for future in done:
                batch = running.pop(future)
                try:
                    results = future.result()
                except BrokenProcessPool as exc:
                    broken = broken or str(exc) or "a worker process died"
                    results = [task.lost(broken) for task in batch]
                for task, result in zip(batch, results, strict=True):
                    yield Completed(task.index, result)
                submit()
        for batch in waiting:
            unfinished.extend(batch)
        for task in unfinished:
            yield Completed(task.index, task.lost(broken or "the process pool stopped"))

    @staticmethod
    def _stop_workers(
        pool: ProcessPoolExecutor,
        running: dict[Future[list[Any]], list[Task]],
        stop: interrupts.Interrupted,
    ) -> None:
        """Pass the driver's signal on to the workers and give them a moment to stop at
        their next safe point (each finalizes the recording it writes); what they say
        about their outputs joins the driver's one line. Workers that do not stop in
        time are terminated when the pool is left."""
        for pid in list(getattr(pool, "_processes", None) or {}):  # no public table
            with contextlib.suppress(OSError):
                os.kill(pid, stop.signum)
        wait(running, timeout=STOP_GRACE_S)
        for future in running:
            if future.done() and not future.cancelled():
                error = future.exception()
                if isinstance(error, interrupts.Interrupted):
                    stop.notes.extend(error.notes)


def executor_for(spec: str, jobs: int = 1, tasks: int | None = None) -> Executor:
    """The executor `--executor SPEC --jobs N` names: "local" (N processes on this
    machine, at most one per usable CPU and per task), "ray" (Ray on this machine, or the
    cluster `ray.init()` finds) or "ray://HOST:PORT" (a Ray cluster, through Ray Client)."""
    if spec == LOCAL:
        workers = min(jobs, usable_cpus(), tasks if tasks is not None else jobs)
        return ProcessExecutor(workers) if workers > 1 else InlineExecutor()
    if spec == "ray" or spec.startswith("ray://"):
        try:
            # Ray is optional and heavy: imported only when asked for.
            from aeroexec.replay.ray_executor import RayExecutor
        except ImportError as exc:
            raise AeroexecError(
                f"--executor {spec} needs Ray ({exc}): pip install 'aeroexec[ray]'"
            ) from None
        return RayExecutor(None if spec == "ray" else spec)
    raise AeroexecError(f"--executor: expected local, ray or ray://HOST:PORT, got {spec!r}")


def replay_many(
    paths: Sequence[str],
    options: ReplayOptions,
    *,
    jobs: int = 1,
    out_dir: str | None = None,
    on_done: Callable[[ReplayResult], None] | None = None,
    executor: Executor | None = None,
) -> list[ReplayResult]:
    """Replay every recording and return the results in the order of `paths`, whatever
    finishes first. `jobs`: processes on this machine (when no `executor` is given; an
    executor given is used as it is, already started). `out_dir`: write each replay to
    `out_dir/<recording stem>.mcap`. `on_done` is told each result as it finishes."""
    if executor is None:
        with executor_for(LOCAL, jobs, len(paths)) as started:
            return replay_many(paths, options, out_dir=out_dir, on_done=on_done, executor=started)
    tasks = make_tasks(paths, options, out_dir, absolute=executor.needs_absolute_paths)
    results: list[ReplayResult | None] = [None] * len(tasks)
    for done in executor.run(tasks):
        results[done.index] = done.result
        if on_done is not None:
            on_done(done.result)
    missing = [tasks[i].recording for i, r in enumerate(results) if r is None]
    if missing:  # an executor that loses a task is a bug, not a verdict
        raise RuntimeError(f"{executor.name} executor returned no result for {missing[:3]}")
    return [r for r in results if r is not None]
