"""One recording to replay, as handed to a worker, and what a worker does with it.

The executors (executors.py, ray_executor.py) run any `Task`: an index, `run()`, and the
result that stands for a task they could not run. `ReplayTask` is replay's; `aeroexec
fuzz` hands them its search chunks the same way (aeroexec/fuzz/search.py).

A `ReplayTask` is small and picklable (names and options, never the recording's bytes),
so every executor — this process, a process pool, a Ray cluster — ships the same thing
and runs the same `run_task`. `run_task` never raises for a recording: whatever goes
wrong with one (unreadable, not MCAP, a store that cannot be reached, a bug met on this
input) is that recording's error result, and the rest of the batch goes on.
"""

from __future__ import annotations

import functools
import gc
import itertools
import os
import tempfile
import traceback
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Protocol

from aeroexec.errors import AeroexecError
from aeroexec.progress import ProgressFactory
from aeroexec.properties.check import check_recording
from aeroexec.properties.report import recording_json
from aeroexec.properties.spec import PropertySet, load_property_documents
from aeroexec.replay.engine import (
    ReplayOptions,
    ReplayResult,
    SessionWatch,
    output_for,
    replay_file,
)
from aeroexec.replay.remote import fetched, is_url

#: At most this many recordings per hand-over to a worker, and at least this many
#: hand-overs per worker (so that none waits idle on a long batch at the end).
MAX_BATCH = 8
BATCHES_PER_WORKER = 16
#: Starts the note on a result that Ray had to run again after its worker failed.
RETRY_NOTE = "retried after a worker failure"
#: A process that runs many replays collects its garbage cycles after every this many.
#: A replay leaves cycles (an executive and its behaviors point at each other) that the
#: catalog loader's collector pause (gc_pause.py) moves to the oldest generation, which
#: Python collects only when it has grown by a quarter: ~150 KB per short replay would
#: pile up for hundreds of replays. A full collection costs ~100 ms in a process with
#: the replay stack loaded, as much as a short replay; every 16 it is ~5 %, and memory
#: stays flat however many replays a process runs (benchmarks/explore.py).
COLLECT_EVERY = 16
_replays = itertools.count(1)


class Task(Protocol):
    """What an executor runs: small and picklable, so it can go to another process or a
    Ray worker; `run` never raises for a problem of its own input (that is its result)."""

    @property
    def index(self) -> int: ...

    def run(self, progress: ProgressFactory | None = None) -> Any:
        """Do the work here (`progress`: how far one long task is, when run inline)."""
        ...

    def lost(self, why: str) -> Any:
        """The result of a task whose worker was lost (`why`: how)."""
        ...

    def failed(self, text: str) -> Any:
        """The result of a task that could not run, said in `text`."""
        ...

    def retried(self, result: Any, attempt: int) -> Any:
        """`result`, noting it took `attempt` runs (its worker died on the others)."""
        ...


@dataclass(frozen=True, slots=True)
class ReplayTask:
    """Replay `recording` (the name the report shows, as the user gave it), read from
    `location` (where a worker finds it: the same path, an absolute path, or a URL)."""

    index: int
    recording: str
    location: str
    options: ReplayOptions

    def run(
        self, progress: ProgressFactory | None = None, watch: SessionWatch | None = None
    ) -> ReplayResult:
        return run_task(self, progress, watch)

    def lost(self, why: str) -> ReplayResult:
        return _failed(
            self,
            f"not replayed: {why} (killed, or out of memory?); --jobs 1 or --executor ray "
            "(which retries) tells which recording",
        )

    def failed(self, text: str) -> ReplayResult:
        return _failed(self, text)

    def retried(self, result: ReplayResult, attempt: int) -> ReplayResult:
        return with_retry_note(result, attempt)


@dataclass(frozen=True, slots=True)
class Completed:
    """A finished task: its position in the batch and its result."""

    index: int
    result: Any


def make_tasks(
    paths: Sequence[str],
    options: ReplayOptions,
    out_dir: str | None = None,
    *,
    absolute: bool = False,
) -> list[ReplayTask]:
    """One task per recording, in order. `absolute`: workers may run in another
    directory (Ray), so local paths and outputs are made absolute; reports still show
    the names given."""
    tasks = []
    for index, path in enumerate(paths):
        opts = replace(options, output=output_for(path, out_dir)) if out_dir else options
        location = path
        if absolute and not is_url(path):
            location = os.path.abspath(path)
            if opts.output is not None:
                opts = replace(opts, output=os.path.abspath(opts.output))
        tasks.append(ReplayTask(index, path, location, opts))
    return tasks


def run_task(
    task: ReplayTask, progress: ProgressFactory | None = None, watch: SessionWatch | None = None
) -> ReplayResult:
    """Replay one recording; every problem with it is its error result. `progress` and
    `watch` (only where the task runs in this process): see `replay_recording`. With
    properties (`ReplayOptions.properties`), the replay's recording is checked here,
    where it was written (a scratch file when the task has no output), and the verdicts
    travel back with the result."""
    if next(_replays) % COLLECT_EVERY == 0:
        gc.collect()
    if not task.options.properties:
        return _replay(task, progress, watch)
    with tempfile.TemporaryDirectory(prefix="aeroexec-replay-") as scratch:
        kept = task.options.output is not None
        if not kept:
            output = output_for(task.recording, scratch)
            task = replace(task, options=replace(task.options, output=output))
        result = _replay(task, progress, watch)
        if result.error is not None or result.output is None:
            return result if kept else replace(result, output=None)
        try:
            report = check_recording(result.output, _property_set(task.options.properties))
        except AeroexecError as exc:  # the replay's own file could not be read back
            return replace(result, output=None, error=f"checking its properties: {exc}")
        # Named after what the user gave: the file they asked for, or the replay of theirs.
        name = result.output if kept else f"{task.recording} (replay)"
        return replace(
            result,
            output=result.output if kept else None,
            properties=recording_json(replace(report, recording=name)),
        )


@functools.lru_cache(maxsize=4)
def _property_set(documents: tuple[tuple[str, str], ...]) -> PropertySet:
    """The properties of a task, loaded once per worker process for all its tasks."""
    return load_property_documents(documents)


def _replay(
    task: ReplayTask, progress: ProgressFactory | None, watch: SessionWatch | None
) -> ReplayResult:
    try:
        if is_url(task.location):
            with fetched(task.location) as local:
                replayed = replay_file(local, task.options, progress, watch)
                return renamed(replayed, local, task.recording)
        result = replay_file(task.location, task.options, progress, watch)
        if task.location != task.recording:
            result = renamed(result, task.location, task.recording)
        return result
    except AeroexecError as exc:  # the store could not give the file
        text = exc.message if exc.mark is not None and exc.mark.file == task.location else str(exc)
        return _failed(task, text)
    except Exception as exc:  # a bug met on this input: report it, replay the others
        return _failed(task, f"replay failed: {_bug(exc)} (please report this, with the file)")


def batch_size(tasks: int, workers: int) -> int:
    """Recordings per hand-over to a worker: 1 for small corpora (no worker waits on a
    batch at the end), up to MAX_BATCH when there are many (each hand-over costs the driver
    ~0.7 ms of CPU in a process pool, and measured ~5 ms of wall time on a local Ray)."""
    return max(1, min(MAX_BATCH, tasks // (workers * BATCHES_PER_WORKER)))


def run_batch(batch: Sequence[Task]) -> list[Any]:
    """A worker's share: a few tasks, one after the other."""
    return [task.run() for task in batch]


def _failed(task: ReplayTask, error: str) -> ReplayResult:
    mode = task.options.mode.value if task.options.mode is not None else None
    return ReplayResult(recording=task.recording, error=error, mode=mode)


def _bug(exc: Exception) -> str:
    frames = traceback.extract_tb(exc.__traceback__)
    where = f" at {Path(frames[-1].filename).name}:{frames[-1].lineno}" if frames else ""
    return f"{type(exc).__name__}: {exc}{where}"


def renamed(result: ReplayResult, location: str, recording: str) -> ReplayResult:
    """`result` as if the file had been read under the name `recording` (messages that
    quote where the worker read it quote the name instead)."""

    def name(text: str) -> str:
        return text.replace(location, recording)

    return replace(
        result,
        recording=recording,
        error=name(result.error) if result.error is not None else None,
        notes=tuple(name(n) for n in result.notes),
    )


def with_retry_note(result: ReplayResult, attempt: int) -> ReplayResult:
    """Say on `result` that it took `attempt` runs (a worker died during the others)."""
    return replace(result, notes=(*result.notes, f"{RETRY_NOTE} (attempt {attempt})"))


def retried(results: Sequence[ReplayResult]) -> list[str]:
    """The recordings that had to be run again after a worker failure."""
    return [r.recording for r in results if any(n.startswith(RETRY_NOTE) for n in r.notes)]
