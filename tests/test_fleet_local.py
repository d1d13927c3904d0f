"""`--jobs N` on this machine: how many workers, and what happens when one dies, when the
user interrupts, and when a replay meets a bug."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from fleet_corpus import Corpus, make_corpus
from fleet_http import Server, serving, wait_for
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.replay import tasks
from aeroexec.replay.engine import Mode, ReplayOptions, ReplayResult
from aeroexec.replay.executors import (
    InlineExecutor,
    ProcessExecutor,
    executor_for,
    replay_many,
    usable_cpus,
)

BIN = Path(sys.executable).parent


@pytest.fixture(scope="module")
def corpus(tmp_path_factory: pytest.TempPathFactory) -> Corpus:
    return make_corpus(tmp_path_factory.mktemp("local") / "flights", 12)


@pytest.fixture
def held(corpus: Corpus) -> Iterator[Server]:
    pytest.importorskip("fsspec", reason="fsspec is not installed (pip install 'aeroexec[ray]')")
    pytest.importorskip("aiohttp", reason="fsspec's HTTP filesystem needs aiohttp")
    with serving(corpus.directory.parent) as server:
        yield server


def url_of(server: Server, corpus: Corpus, index: int) -> tuple[str, str]:
    path = f"/{corpus.directory.name}/{Path(corpus.files[index]).name}"
    return server.url + path, path


def test_never_more_workers_than_cpus_or_recordings() -> None:
    many = executor_for("local", jobs=64, tasks=1000)
    if usable_cpus() > 1:
        assert isinstance(many, ProcessExecutor) and many.workers == usable_cpus()
    else:
        assert isinstance(many, InlineExecutor)
    assert isinstance(executor_for("local", jobs=4, tasks=1), InlineExecutor)
    assert isinstance(executor_for("local", jobs=1, tasks=1000), InlineExecutor)


def test_a_bug_met_on_one_recording_is_its_error_result(
    corpus: Corpus, monkeypatch: pytest.MonkeyPatch
) -> None:
    real = tasks.replay_file
    victim = corpus.files[1]

    def replay_file(
        path: str, options: ReplayOptions, progress: None = None, watch: None = None
    ) -> ReplayResult:
        if path == victim:
            return {}["no such key"]  # what a bug in replay looks like from here
        return real(path, options, progress, watch)

    monkeypatch.setattr(tasks, "replay_file", replay_file)
    results = replay_many(corpus.files[:3], ReplayOptions(mode=Mode.open))
    assert [r.error is None for r in results] == [True, False, True]
    assert results[1].error == (
        f"replay failed: KeyError: 'no such key' at {Path(__file__).name}:"
        f"{replay_file.__code__.co_firstlineno + 4} (please report this, with the file)"
    )


def test_a_pool_worker_that_dies_gives_error_results_not_a_crash(
    corpus: Corpus, held: Server
) -> None:
    url, path = url_of(held, corpus, 0)
    held.hold.add(path)
    others = list(corpus.files[1:4])
    done: list[ReplayResult] = []
    killed: list[int] = []
    options = ReplayOptions(mode=Mode.open)
    with ProcessExecutor(2) as pool:
        workers = list(pool._pool._processes)  # type: ignore[union-attr]

        def kill_one() -> None:
            try:
                if wait_for(held.held.is_set) and wait_for(lambda: len(done) == len(others)):
                    for pid in workers:  # the pool breaks whichever dies: kill them all
                        os.kill(pid, signal.SIGKILL)
                        killed.append(pid)
            finally:
                held.release()

        killer = threading.Thread(target=kill_one)
        killer.start()
        results = replay_many([url, *others], options, executor=pool, on_done=done.append)
        killer.join()
    assert killed
    assert results[0].error is not None and results[0].error.startswith("not replayed: ")
    assert "--jobs 1 or --executor ray" in results[0].error
    assert [r.error for r in results[1:]] == [None, None, None]


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGKILL])
def test_a_signal_stops_a_parallel_replay_and_its_workers(
    corpus: Corpus, held: Server, signum: signal.Signals
) -> None:
    """SIGTERM: the driver stops its workers (one is stuck in a slow download) and exits
    143 at once. SIGKILL: the driver cannot, and the workers die with it."""
    url, path = url_of(held, corpus, 0)
    held.hold.add(path)
    started = time.monotonic()
    replay = subprocess.Popen(
        [str(BIN / "aeroexec"), "replay", url, *corpus.files[1:3], "--jobs", "2"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert wait_for(held.held.is_set, 60), "the held download never started"
        children = [int(p) for p in _children(replay.pid)]
        assert len(children) == 2
        replay.send_signal(signum)
        out, err = replay.communicate(timeout=30)
        gone = wait_for(lambda: not any(_alive(pid) for pid in children), 10)
    finally:
        if replay.poll() is None:
            replay.kill()
        held.release()
    assert time.monotonic() - started < 30  # not the 60 s the download is held
    assert gone, "a worker outlived its driver"
    if signum == signal.SIGTERM:
        assert replay.returncode == 128 + signal.SIGTERM
        assert out == ""
        assert err.strip().splitlines()[-1] == "aeroexec replay: interrupted by SIGTERM"
    else:
        assert replay.returncode == -signal.SIGKILL


def _alive(pid: int) -> bool:
    """Running, and not a zombie waiting for its parent to collect it."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


def _children(pid: int) -> list[str]:
    found = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = Path(f"/proc/{entry}/stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                found.append(entry)
    return found


def test_results_are_the_same_in_any_executor_order(corpus: Corpus) -> None:
    options = ReplayOptions(catalog=str(corpus.narrowed), mode=Mode.open)
    one = [r.as_dict() for r in replay_many(corpus.files, options)]
    two = [r.as_dict() for r in replay_many(corpus.files, options, jobs=2)]
    assert one == two
    assert json.dumps(one).count('"equal": false') == len(corpus.differing) + len(corpus.broken)


@pytest.mark.parametrize(
    ("args", "hidden", "expected"),
    [
        (
            ["--executor", "ray"],
            ["ray"],
            "aeroexec replay: error: --executor ray needs Ray (import of ray halted; None in "
            "sys.modules): pip install 'aeroexec[ray]'",
        ),
        (
            ["s3://bucket/flights/"],
            ["fsspec"],
            "aeroexec replay: error: recordings named by URL need fsspec: pip install "
            "'aeroexec[ray]'",
        ),
    ],
)
def test_a_missing_optional_dependency_is_one_line(
    corpus: Corpus,
    monkeypatch: pytest.MonkeyPatch,
    args: list[str],
    hidden: list[str],
    expected: str,
) -> None:
    for module in hidden:  # as if not installed: importing it raises ImportError
        monkeypatch.setitem(sys.modules, module, None)
    monkeypatch.delitem(sys.modules, "aeroexec.replay.ray_executor", raising=False)
    result = CliRunner().invoke(app, ["replay", *corpus.files[:2], *args])
    assert result.exit_code == 2
    assert result.stderr.strip().splitlines() == [expected]
