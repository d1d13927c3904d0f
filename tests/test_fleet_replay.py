"""Same verdict everywhere: `replay --jobs 1`, `--jobs 2`, `--shard K/N` + `report merge`
and `--executor ray` give the same report, byte for byte, on a corpus of 200 generated
recordings with planted differences and planted broken files (tests/fleet_corpus.py).

Replays are open loop: it runs no code from the recordings, so the verdicts do not depend
on how far a recording's own mission script is trusted; the executors under test run
closed-loop replays through the very same `run_task`.
"""

from __future__ import annotations

import json
import logging
import os
import shutil
import signal
import tempfile
import threading
import xml.etree.ElementTree as ET
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from fleet_corpus import Corpus, make_corpus
from fleet_http import Server, busy_ray_workers, serving, wait_for
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.replay.engine import Mode, ReplayOptions, ReplayResult
from aeroexec.replay.executors import replay_many
from aeroexec.replay.shard import parse_shard, shard_of, slice_for
from aeroexec.replay.tasks import batch_size, retried

COUNT = 200
runner = CliRunner()


def cli(*args: str) -> tuple[int, str, str]:
    result = runner.invoke(app, list(args))
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(
        result.exception
    )
    return result.exit_code, result.stdout, result.stderr


def one_error_line(stderr: str) -> str:
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    assert "Traceback" not in stderr
    return lines[0]


@pytest.fixture(scope="module")
def corpus(tmp_path_factory: pytest.TempPathFactory) -> Corpus:
    return make_corpus(tmp_path_factory.mktemp("fleet") / "flights", COUNT)


def replay(corpus: Corpus, *extra: str) -> tuple[int, str, str]:
    return cli(
        "replay",
        str(corpus.directory),
        "--catalog",
        str(corpus.narrowed),
        "--mode",
        "open",
        "--check",
        *extra,
    )


@pytest.fixture(scope="module")
def reference(corpus: Corpus) -> tuple[int, str, str]:
    """The report of one process (`--jobs 1`): what every other way must give."""
    return replay(corpus, "--format", "json")


@pytest.fixture(scope="module")
def local_ray() -> Iterator[None]:
    """Ray on this machine, started the way the issue describes (2 CPUs), and stopped."""
    ray = pytest.importorskip("ray", reason="Ray is not installed (pip install 'aeroexec[ray]')")
    # A short directory of our own: Ray's socket paths must stay under 107 characters.
    temp = tempfile.mkdtemp(prefix="ray-fleet-")
    ray.init(
        num_cpus=2,
        include_dashboard=False,
        log_to_driver=False,
        logging_level=logging.WARNING,
        _temp_dir=temp,
    )
    try:
        yield
    finally:
        ray.shutdown()
        shutil.rmtree(temp, ignore_errors=True)


# -- the reference is right ----------------------------------------------------------------
def test_the_reference_finds_what_was_planted(corpus: Corpus, reference: tuple) -> None:
    code, out, err = reference
    assert code == 2  # broken files: an input could not be read
    document = json.loads(out)
    rows = document["recordings"]
    assert [r["recording"] for r in rows] == list(corpus.files)
    assert {r["recording"] for r in rows if r["error"] is None and not r["equal"]} == (
        corpus.differing
    )
    assert {r["recording"] for r in rows if r["error"] is not None} == corpus.broken
    assert len(corpus.differing) >= 40 and len(corpus.broken) == 2
    for row in rows:
        if row["recording"] in corpus.differing:
            assert any("now rejected" in d["message"] for d in row["differences"]), row
        if row["recording"] in corpus.incomplete:
            assert row["equal"] and row["notes"][0].startswith("incomplete recording"), row
    assert sorted(err.strip().splitlines()) == sorted(
        f"{r['recording']}: error: {r['error']}" for r in rows if r["error"]
    )


# -- the same report, however it is run ------------------------------------------------------
def test_jobs_2_gives_the_same_report(corpus: Corpus, reference: tuple) -> None:
    assert replay(corpus, "--format", "json", "--jobs", "2") == reference


def test_shards_merge_into_the_same_report(
    corpus: Corpus, reference: tuple, tmp_path: Path
) -> None:
    shards = []
    held: list[set[str]] = []
    for k in (1, 2, 3):
        code, out, _ = replay(corpus, "--format", "json", "--shard", f"{k}/3")
        document = json.loads(out)
        names = {r["recording"] for r in document["recordings"]}
        assert names and {corpus.files[p] for p in document["shard"]["positions"]} == names
        has_problem = bool(names & corpus.broken)
        assert code == (2 if has_problem else 1 if names & corpus.differing else 0)
        held.append(names)
        path = tmp_path / f"shard-{k}.json"
        path.write_text(out, encoding="utf-8")
        shards.append(str(path))
    assert set.union(*held) == set(corpus.files) and sum(map(len, held)) == len(corpus.files)
    # Given in any order, the shards merge into the unsharded report.
    merged = cli("report", "merge", *reversed(shards), "--check", "--format", "json")
    assert merged == reference
    suite = ET.fromstring(cli("report", "merge", *shards, "--format", "junit")[1])
    assert (suite.get("tests"), suite.get("errors")) == (str(COUNT), "2")
    assert suite.get("failures") == str(len(corpus.differing))


def test_ray_gives_the_same_report(corpus: Corpus, reference: tuple, local_ray: None) -> None:
    assert replay(corpus, "--format", "json", "--executor", "ray") == reference


def test_ray_checks_properties_where_each_replay_runs(corpus: Corpus, local_ray: None) -> None:
    # --spec: each replay's recording is checked on the Ray worker that wrote it (a
    # scratch file there), and the verdicts come back with its result.
    spec = ["--spec", "aeroexec:safety", "--format", "json"]
    here = replay(corpus, *spec, "--jobs", "1")
    assert replay(corpus, *spec, "--executor", "ray") == here
    document = json.loads(here[1])
    checked = document["properties"]["recordings"]
    replayed = [r["recording"] for r in document["recordings"] if r["error"] is None]
    assert [c["recording"] for c in checked] == [f"{name} (replay)" for name in replayed]
    assert all(len(c["verdicts"]) == 4 for c in checked)


# -- shards ---------------------------------------------------------------------------------
def test_a_recording_stays_in_its_shard_when_recordings_are_added(corpus: Corpus) -> None:
    names = list(corpus.files)
    before = {name: shard_of(name, 4) for name in names}
    grown = sorted([*names, *(f"{corpus.directory}/later-{i:04}.mcap" for i in range(300))])
    for k in (1, 2, 3, 4):
        part = slice_for(grown, parse_shard(f"{k}/4"), {})
        held = {grown[p] for p in part.positions}
        assert {n for n in names if before[n] == k} == held & set(names)
    # Hash slicing balances statistically: each of 4 shards holds 25% +- a few points.
    counts = [len(slice_for(grown, parse_shard(f"{k}/4"), {}).positions) for k in (1, 2, 3, 4)]
    assert sum(counts) == len(grown) and all(0.18 < c / len(grown) < 0.32 for c in counts)


def test_a_shard_is_the_same_however_the_directory_is_spelled() -> None:
    names = [f"recordings/flight-{i}.mcap" for i in range(50)]
    for spelling in ("./recordings/flight-{}.mcap", "recordings//flight-{}.mcap"):
        assert [shard_of(spelling.format(i), 7) for i in range(50)] == [
            shard_of(n, 7) for n in names
        ]
    assert len({shard_of(n, 7) for n in names}) == 7  # and the hash does spread them


@pytest.mark.parametrize("value", ["0/3", "4/3", "a/b", "3", "1/0", ""])
def test_bad_shard_values(corpus: Corpus, value: str) -> None:
    code, _, err = cli("replay", str(corpus.files[0]), "--shard", value)
    assert code == 2
    assert one_error_line(err).startswith("aeroexec replay: error: --shard: ")


def test_bad_executor_value(corpus: Corpus) -> None:
    code, _, err = cli("replay", str(corpus.files[0]), "--executor", "dask")
    assert code == 2
    assert one_error_line(err) == (
        "aeroexec replay: error: --executor: expected local, ray or ray://HOST:PORT, got 'dask'"
    )


# -- merge: exit codes, output, refusals -----------------------------------------------------
@pytest.fixture(scope="module")
def small(corpus: Corpus, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Four readable recordings of the corpus, one of them planted to differ."""
    directory = tmp_path_factory.mktemp("small")
    differing = sorted(corpus.differing)[0]
    same = [f for f in corpus.files if f not in corpus.differing | corpus.broken][:3]
    for name in [differing, *same]:
        shutil.copy(name, directory / Path(name).name)
    return directory


def shard_files(directory: Path, out: Path, count: int, *extra: str) -> list[str]:
    files = []
    for k in range(1, count + 1):
        code, text, err = cli(
            "replay",
            str(directory),
            "--mode",
            "open",
            "--shard",
            f"{k}/{count}",
            "--format",
            "json",
            *extra,
        )
        assert code == 0, err
        path = out / f"{directory.name}-{k}-of-{count}{'-x' if extra else ''}.json"
        path.write_text(text, encoding="utf-8")
        files.append(str(path))
    return files


def test_merge_exit_codes_and_output_file(small: Path, corpus: Corpus, tmp_path: Path) -> None:
    catalog = ("--catalog", str(corpus.narrowed))
    differing = shard_files(small, tmp_path, 2, *catalog)
    assert cli("report", "merge", *differing)[0] == 0
    code, out, _ = cli("report", "merge", *differing, "--check")
    assert code == 1 and out.strip().endswith(
        "4 recordings: 1 with differences, 3 without, 0 unreadable"
    )
    same = shard_files(small, tmp_path, 2)
    assert cli("report", "merge", *same, "--check")[0] == 0
    target = tmp_path / "replay.xml"
    code, out, _ = cli("report", "merge", *differing, "--format", "junit", "-o", str(target))
    assert (code, out) == (0, "")
    suite = ET.fromstring(target.read_text(encoding="utf-8"))
    assert (suite.get("tests"), suite.get("failures")) == ("4", "1")
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".replay.xml")] == []


@pytest.mark.parametrize("fmt", ["junit", "text"])
def test_merged_junit_and_text_are_the_unsharded_ones(
    small: Path, corpus: Corpus, tmp_path: Path, fmt: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    # JUnit's timestamp and times are wall-clock facts; this makes both reports exact.
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")
    catalog = ("--catalog", str(corpus.narrowed))
    whole = cli("replay", str(small), "--mode", "open", "--format", fmt, *catalog)
    assert whole[0] == 0 and "1 difference" in whole[1]
    shards = shard_files(small, tmp_path, 3, *catalog)
    assert cli("report", "merge", *shards, "--format", fmt) == whole


def test_merge_refuses_what_is_not_one_whole_run(
    small: Path, corpus: Corpus, tmp_path: Path
) -> None:
    thirds = shard_files(small, tmp_path, 3)
    halves = shard_files(small, tmp_path, 2)
    other = shard_files(small, tmp_path, 3, "--tolerance", "0.2")

    def refused(*files: str) -> str:
        code, out, err = cli("report", "merge", *files)
        assert (code, out) == (2, "")
        return one_error_line(err)

    assert refused(thirds[0], thirds[2]) == (
        "aeroexec report merge: error: shard(s) 2 of 3 missing: the merged report would "
        "not be whole"
    )
    assert refused(*thirds, thirds[1]) == (
        f"{thirds[1]}: error: shard 2/3 given twice (also {thirds[1]})"
    )
    assert refused(halves[0], thirds[1], thirds[2]).endswith(
        f"error: shards of different runs: shard counts differ from {halves[0]}"
    )
    assert refused(thirds[0], other[1], thirds[2]) == (
        f"{other[1]}: error: shards of different runs: settings (catalog, mode or "
        f"tolerances) differ from {thirds[0]}"
    )
    bigger = tmp_path / "bigger"
    shutil.copytree(small, bigger)
    shutil.copy(corpus.files[-1], bigger / "extra.mcap")
    grown = shard_files(bigger, tmp_path, 3)
    assert "corpora (the recordings each shard saw differ)" in refused(thirds[0], *grown[1:])


def test_merge_refuses_unreadable_reports(small: Path, tmp_path: Path) -> None:
    plain = tmp_path / "plain.json"
    plain.write_text(cli("replay", str(small), "--mode", "open", "--format", "json")[1])
    broken = tmp_path / "broken.json"
    broken.write_text('{"shard": ')
    cases = {
        str(plain): f"{plain}: error: not a shard report (made by `aeroexec replay ... "
        "--shard K/N --format json`)",
        str(broken): f"{broken}:1:11: error: not JSON: Expecting value",
        str(tmp_path / "missing.json"): f"{tmp_path / 'missing.json'}: error: cannot read: "
        "No such file or directory",
    }
    for path, expected in cases.items():
        code, _, err = cli("report", "merge", path)
        assert code == 2
        assert one_error_line(err) == expected


# -- Ray: workers that die ---------------------------------------------------------------------
RETRIED = "retried after a worker failure (attempt 2)"


@pytest.fixture
def held(corpus: Corpus) -> Iterator[Server]:
    """An HTTP server over the corpus; a test names the download it holds open."""
    with serving(corpus.directory.parent) as server:
        yield server


def kill_held_workers(
    server: Server, path: str, others_done: Callable[[int], bool], killed: list[int], times: int
) -> None:
    """`times` over: once the download of `path` is held and `others_done(i)`, kill the one
    Ray worker still busy (the one stuck in the download), holding the next download of
    `path` again; then let the server go on."""
    try:
        busy: list[int] = []

        def alone() -> bool:
            busy[:] = busy_ray_workers("replay_on_worker")
            return len(busy) == 1

        for i in range(times):
            if not (wait_for(server.held.is_set) and wait_for(lambda i=i: others_done(i))):
                return
            if not wait_for(alone):
                return
            server.held.clear()
            if i + 1 < times:
                server.hold.add(path)
            os.kill(busy[0], signal.SIGKILL)
            killed.append(busy[0])
    finally:
        server.release()


def row_of(reference: tuple, name: str) -> dict:
    return next(r for r in json.loads(reference[1])["recordings"] if r["recording"] == name)


def test_a_killed_worker_is_retried_and_the_report_says_so(
    corpus: Corpus, reference: tuple, held: Server, local_ray: None
) -> None:
    name = sorted(corpus.differing)[0]
    path = f"/{corpus.directory.name}/{Path(name).name}"
    held.hold.add(path)
    killed: list[int] = []
    killer = threading.Thread(
        target=kill_held_workers, args=(held, path, lambda _: True, killed, 1)
    )
    killer.start()
    code, out, err = cli(
        "replay",
        held.url + path,
        "--catalog",
        str(corpus.narrowed),
        "--mode",
        "open",
        "--format",
        "json",
        "--executor",
        "ray",
    )
    killer.join()
    assert len(killed) == 1, "no Ray worker was found stuck in the held download"
    assert code == 0
    (row,) = json.loads(out)["recordings"]
    expected = row_of(reference, name)
    assert row["notes"] == [*expected["notes"], RETRIED]
    assert row["differences"] == expected["differences"] and not row["equal"]
    assert err.strip().splitlines()[-1] == f"note: retried after a worker failure: {held.url}{path}"


def test_a_recording_whose_worker_always_dies_is_one_error_result(
    corpus: Corpus, reference: tuple, held: Server, local_ray: None
) -> None:
    """With retries off and batches of 2 (71 recordings on 2 CPUs): the batch dies, its two
    recordings are tried alone, the held one dies again and is an error, its batch-mate is
    replayed (and says so), and the job goes on."""
    name = sorted(corpus.differing)[1]
    path = f"/{corpus.directory.name}/{Path(name).name}"
    held.hold.add(path)
    others = [f for f in corpus.files if f not in corpus.broken and f != name][:70]
    assert batch_size(1 + len(others), 2) == 2
    done: list[ReplayResult] = []
    killed: list[int] = []
    # First: everything but the held recording's batch-mate is done; then: the mate too.
    waits = (len(others) - 1, len(others))
    killer = threading.Thread(
        target=kill_held_workers,
        args=(held, path, lambda i: len(done) >= waits[i], killed, 2),
    )
    killer.start()
    options = ReplayOptions(catalog=str(corpus.narrowed), mode=Mode.open)
    from aeroexec.replay.ray_executor import RayExecutor  # Ray is optional: local_ray checked

    with RayExecutor(max_retries=0) as ray_executor:
        results = replay_many(
            [held.url + path, *others], options, executor=ray_executor, on_done=done.append
        )
    killer.join()
    assert len(killed) == 2, "no Ray worker was found stuck in the held download"
    assert results[0].error == (
        "not replayed: the Ray worker failed on each of 2 attempts (WorkerCrashedError)"
    )
    mate = row_of(reference, others[0])
    assert results[1].as_dict() == {**mate, "notes": [*mate["notes"], RETRIED]}
    for result, other in zip(results[2:], others[1:], strict=True):  # the job went on
        assert result.as_dict() == row_of(reference, other)
    assert retried(results) == [others[0]]
