"""`--executor ray` and `--executor ray://HOST:PORT`: replays as Ray tasks.

Ray tasks running the same `run_task` as every other executor, a few recordings each
(up to 8, when there are many: a Ray task costs ~5 ms of a 2-CPU machine's time, as much
as half a short replay). Ray does the scheduling, the placement and the retries; this
module only submits, collects and says what happened:

* results stream back as tasks finish (`ray.wait`), at most a few tasks per CPU of the
  cluster in flight, so the driver holds one small result per recording and the object
  store next to nothing;
* a broken recording is an error *result* (`run_task` never raises for one), so Ray never
  retries it and the job never fails because of it;
* a worker that dies (killed, out of memory, its node lost) is Ray's to handle: the task
  is retried (`max_retries`, Ray's default 3) and each of its recordings notes that it
  was replayed again. When every attempt of a batch dies, its recordings are tried again
  one per task, so that only a recording that kills its worker every time ends as an
  error result naming Ray's reason;
* `ray://` connects through Ray Client and ships this process's aeroexec package to the
  workers (`runtime_env` `py_modules`), so the cluster replays with the code under test,
  not with whatever aeroexec its image has; its other dependencies must be installed
  there. A probe task checks that before any recording is submitted.

Ray is an optional dependency (`pip install "aeroexec[ray]"`); this module and
`ray_client_check` (why a `ray://` connection fails) are the only ones that import it,
and only `--executor ray...` imports them.
"""

from __future__ import annotations

import contextlib
import logging
from collections import deque
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import ray
import ray.exceptions

import aeroexec
from aeroexec.errors import AeroexecError
from aeroexec.interrupts import check
from aeroexec.replay import ray_client_check
from aeroexec.replay.tasks import Completed, Task, batch_size, run_batch

#: Ray's default for tasks, said out loud: how often a task whose worker died is rerun.
MAX_RETRIES = 3
#: Connections tried when the head's Ray Client server for this client exits at start.
CLIENT_SERVER_ATTEMPTS = 2
#: Ray tasks in flight per CPU of the cluster (and at least MIN_IN_FLIGHT).
IN_FLIGHT_PER_CPU = 2
MIN_IN_FLIGHT = 16
#: How long (s) the driver waits for results before looking for a signal (Ctrl-C).
CHECK_INTERVAL_S = 0.2


def _attempt() -> int:
    """Which run of the current task this is (0: the first). Ray has no public API for it
    yet; its core worker has, and Ray's own tests use it. 0 if that ever goes away: the
    report would then miss a retry, never invent one."""
    try:
        worker = ray._private.worker.global_worker.core_worker
        return int(worker.get_current_task_attempt_number())
    except Exception:
        return 0


def replay_on_worker(batch: list[Task]) -> tuple[list[Any], int]:
    """The Ray task: a few tasks' results (recordings', fuzz chunks') and the attempt
    that produced them."""
    return run_batch(batch), _attempt()


def probe() -> str:
    """Runs on a worker before any recording: unpickling it imports this module, hence
    the whole replay stack; which aeroexec version is that?"""
    return aeroexec.__version__


class RayExecutor:
    """Replays on Ray: `address` None is `ray.init()`'s default (the cluster on this
    machine or in RAY_ADDRESS, else a new local Ray for this run); "ray://HOST:PORT" is a
    cluster through Ray Client. Inside an application that already called `ray.init()`,
    that Ray is used as it is and left running."""

    needs_absolute_paths = True

    def __init__(self, address: str | None = None, *, max_retries: int = MAX_RETRIES) -> None:
        self.address = address
        self.name = address or "ray"
        self.max_retries = max_retries
        self._owned = False
        self._remote: Any = None

    def __enter__(self) -> RayExecutor:
        if not ray.is_initialized():
            self._connect()
        self._remote = ray.remote(max_retries=self.max_retries, retry_exceptions=False)(
            replay_on_worker
        )
        try:
            self._check_workers()
        except BaseException:
            self.__exit__(None, None, None)
            raise
        return self

    def __exit__(self, *exc_info: object) -> None:
        if self._owned:
            ray.shutdown()
            self._owned = False

    def _connect(self) -> None:
        where = self.address or "this machine"
        client = self.address is not None and self.address.startswith("ray://")
        if client:
            problem = ray_client_check.problem(str(self.address))
            if problem is not None:
                raise AeroexecError(f"cannot reach Ray on {where}: {problem}")
        try:
            if client:
                self._connect_client()
            else:
                ray.init(
                    address=self.address,
                    # A Ray started for one run has nobody to show a dashboard to.
                    include_dashboard=False,
                    # Workers' prints would land in this process's stdout, in the middle of
                    # a JSON or JUnit report; their failures come back as results anyway.
                    log_to_driver=False,
                    logging_level=logging.WARNING,
                )
        except Exception as exc:  # ConnectionError, a bad address, a version mismatch...
            message = str(exc)
            why = ray_client_check.hint(message) if client else ""
            raise AeroexecError(
                f"cannot start or reach Ray on {where}: {_first_line(exc)}{why}"
            ) from None
        self._owned = True

    def _connect_client(self) -> None:
        package = str(Path(aeroexec.__file__).parent)
        for attempt in range(CLIENT_SERVER_ATTEMPTS):
            try:
                ray.init(address=self.address, runtime_env={"py_modules": [package]})
                return
            except Exception as exc:
                # The head starts a Ray Client server process for each client; now and
                # then (seen on a 2-core CI machine) it exits before serving: it is asked
                # for once more before that is reported. Any other failure is final.
                last = attempt == CLIENT_SERVER_ATTEMPTS - 1
                if last or "Starting Ray client server failed" not in str(exc):
                    raise
                with contextlib.suppress(Exception):
                    ray.shutdown()

    def _check_workers(self) -> None:
        try:
            version = ray.get(ray.remote(probe).remote())
        except ray.exceptions.RayError as exc:
            raise AeroexecError(
                f"the Ray workers of {self.name} cannot run aeroexec's replay: "
                f"{_first_line(exc)} (install aeroexec's dependencies there)"
            ) from None
        if version != aeroexec.__version__:
            raise AeroexecError(
                f"the Ray workers of {self.name} run aeroexec {version}, this is "
                f"{aeroexec.__version__}: replays would not test this version"
            )

    def run(self, tasks: Sequence[Task]) -> Iterator[Completed]:
        if self._remote is None:
            raise RuntimeError("RayExecutor.run outside its `with` block")
        cpus = self._cpus()
        size = batch_size(len(tasks), cpus)
        waiting = deque(list(tasks[i : i + size]) for i in range(0, len(tasks), size))
        running: dict[Any, list[Task]] = {}
        #: Attempts that died before, per task index (its batch's, before it ran alone).
        spent: dict[int, int] = {}

        window = max(MIN_IN_FLIGHT, IN_FLIGHT_PER_CPU * cpus)

        def submit() -> None:
            while waiting and len(running) < window:
                batch = waiting.popleft()
                running[self._remote.remote(batch)] = batch

        submit()
        try:
            while running:
                refs = list(running)
                ready, _ = ray.wait(refs, num_returns=1, timeout=CHECK_INTERVAL_S)
                check()
                if ready:  # and every other one already there, without waiting again
                    ready, _ = ray.wait(refs, num_returns=len(refs), timeout=0)
                for ref in ready:
                    batch = running.pop(ref)
                    yield from self._completed(ref, batch, waiting, spent)
                    submit()
        finally:
            for ref in running:  # interrupted (or the caller stopped reading): stop them
                ray.cancel(ref, force=True)

    def _completed(
        self,
        ref: Any,
        batch: list[Task],
        waiting: deque[list[Task]],
        spent: dict[int, int],
    ) -> Iterator[Completed]:
        """The results of a finished Ray task; a batch whose worker died on every attempt
        goes back to `waiting` one recording per task, so that only the recording that
        kills its worker (if one does) ends as an error."""
        try:
            results, attempt = ray.get(ref)
        except ray.exceptions.RayTaskError as exc:  # not a recording's doing: a bug, or
            for task in batch:  # a cluster that cannot unpickle the task
                yield Completed(task.index, task.failed(f"the Ray task failed: {_first_line(exc)}"))
            return
        except ray.exceptions.RayError as exc:  # its worker died on every attempt
            for task in batch:
                spent[task.index] = spent.get(task.index, 0) + self.max_retries + 1
            if len(batch) > 1:
                waiting.extendleft([task] for task in reversed(batch))
                return
            (task,) = batch
            yield Completed(
                task.index,
                task.failed(
                    f"not replayed: the Ray worker failed on each of {spent[task.index]} "
                    f"attempts ({type(exc).__name__})"
                ),
            )
            return
        for task, result in zip(batch, results, strict=True):
            runs = spent.get(task.index, 0) + attempt + 1
            yield Completed(task.index, task.retried(result, runs) if runs > 1 else result)

    def _cpus(self) -> int:
        return max(1, int(ray.cluster_resources().get("CPU", 1)))


def _first_line(exc: BaseException) -> str:
    lines = [line for line in str(exc).splitlines() if line.strip()]
    return lines[-1].strip() if lines else type(exc).__name__
