"""Recordings named by URL (fsspec: a real HTTP server here, `file://`), and a real Ray
cluster reached through Ray Client (`--executor ray://HOST:PORT`, `ray start --head` in a
subprocess, token authentication on): the verdicts are those of local paths, one process.
"""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest
from fleet_corpus import Corpus, make_corpus
from fleet_http import Server, serving, wait_for
from typer.testing import CliRunner

from aeroexec.cli import app

runner = CliRunner()
BIN = Path(sys.executable).parent


def cli(*args: str) -> tuple[int, str, str]:
    result = runner.invoke(app, list(args))
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(
        result.exception
    )
    return result.exit_code, result.stdout, result.stderr


@pytest.fixture(scope="module")
def corpus(tmp_path_factory: pytest.TempPathFactory) -> Corpus:
    return make_corpus(tmp_path_factory.mktemp("remote") / "flights", 12)


@pytest.fixture(scope="module")
def http(corpus: Corpus) -> Iterator[Server]:
    pytest.importorskip("fsspec", reason="fsspec is not installed (pip install 'aeroexec[ray]')")
    pytest.importorskip("aiohttp", reason="fsspec's HTTP filesystem needs aiohttp")
    with serving(corpus.directory.parent) as server:
        yield server


def options(corpus: Corpus) -> list[str]:
    return ["--catalog", str(corpus.narrowed), "--mode", "open", "--format", "json"]


def rows(out: str) -> list[dict]:
    return json.loads(out)["recordings"]


def named(rows: list[dict], name: dict[str, str]) -> list[dict]:
    """`rows` with each recording renamed by `name` (URL -> local path)."""
    return [{**row, "recording": name.get(row["recording"], row["recording"])} for row in rows]


# -- URLs ------------------------------------------------------------------------------------
def test_a_directory_url_gives_the_verdicts_of_the_local_directory(
    corpus: Corpus, http: Server
) -> None:
    local = cli("replay", str(corpus.directory), *options(corpus))
    code, out, err = cli("replay", f"{http.url}/{corpus.directory.name}/", *options(corpus))
    urls = {f"{http.url}/{corpus.directory.name}/{Path(f).name}": f for f in corpus.files}
    assert [r["recording"] for r in rows(out)] == sorted(urls)
    assert named(rows(out), urls) == rows(local[1])
    assert code == local[0] == 2
    assert err == "".join(
        f"{r['recording']}: error: {r['error']}\n" for r in rows(out) if r["error"]
    )


def test_url_globs_and_file_urls(corpus: Corpus, http: Server) -> None:
    first = [str(corpus.directory / f"flight-0000{i}.mcap") for i in range(4)]
    differing = corpus.differing & set(first)
    assert differing  # the corpus plants one among the first four
    pattern = f"file://{corpus.directory}/flight-0000[0-3].mcap"
    code, out, _ = cli("replay", pattern, "--check", *options(corpus))
    assert [r["recording"] for r in rows(out)] == [f"file://{f}" for f in first]
    assert {r["recording"] for r in rows(out) if not r["equal"]} == {
        f"file://{f}" for f in differing
    }
    assert code == 1


def test_unreadable_urls_are_error_results(corpus: Corpus, http: Server) -> None:
    missing = f"{http.url}/{corpus.directory.name}/nowhere.mcap"
    unknown = "nosuchscheme://bucket/flight.mcap"
    empty = f"file://{corpus.directory}/nothing-*.mcap"
    code, out, err = cli("replay", missing, unknown, empty, corpus.files[0], *options(corpus))
    assert code == 2
    assert [(r["recording"], r["error"]) for r in rows(out)] == [
        (missing, "cannot read: no such file"),
        (unknown, "cannot read: Protocol not known: nosuchscheme"),
        (empty, "no recordings match this pattern"),
        (corpus.files[0], None),
    ]
    assert len(err.strip().splitlines()) == 3 and "Traceback" not in err


# -- a Ray cluster through Ray Client ----------------------------------------------------------
def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def listening(port: int) -> bool:
    with socket.socket() as probe:
        probe.settimeout(0.5)
        return probe.connect_ex(("127.0.0.1", port)) == 0


@pytest.fixture(scope="module")
def cluster() -> Iterator[tuple[str, dict[str, str], Path]]:
    """`ray start --head` (2 CPUs, token authentication) in its own process group, and
    what a client needs: the ray:// address and the environment with the token; and the
    head's temporary folder (its logs)."""
    pytest.importorskip("ray", reason="Ray is not installed (pip install 'aeroexec[ray]')")
    if not (BIN / "ray").exists():
        pytest.skip(f"no `ray` command beside {sys.executable}")
    temp = tempfile.mkdtemp(prefix="ray-head-")  # short: Ray's socket paths must fit
    client_port = free_port()
    env = {k: v for k, v in os.environ.items() if not k.startswith("RAY_")}
    env |= {"RAY_AUTH_MODE": "token", "RAY_AUTH_TOKEN": secrets.token_hex(32)}
    # The head starts a Ray Client server process per client and waits 30 s for it to
    # answer ("Proxy failed to Connect to backend" after that); on a loaded two-core
    # machine its start (importing ray) can take longer (docs/fleet.md, "When Ray Client
    # cannot connect").
    env["RAY_CLIENT_SERVER_CHECK_CHANNEL_TIMEOUT_S"] = "180"
    head = subprocess.Popen(
        [
            str(BIN / "ray"),
            "start",
            "--head",
            "--block",
            f"--port={free_port()}",
            f"--ray-client-server-port={client_port}",
            "--num-cpus=2",
            "--include-dashboard=false",
            "--disable-usage-stats",
            f"--temp-dir={temp}",
        ],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,  # its own process group: stopped below by that id
    )
    try:
        if not wait_for(lambda: listening(client_port) or head.poll() is not None, 120):
            pytest.fail("the Ray head did not open its client port within 120 s")
        if head.poll() is not None:
            pytest.fail(f"`ray start --head` exited with {head.returncode}")
        yield f"ray://127.0.0.1:{client_port}", env, Path(temp)
    finally:
        head.send_signal(signal.SIGTERM)  # `ray start --block` stops what it started
        try:
            head.wait(60)
        except subprocess.TimeoutExpired:
            head.kill()
        with contextlib.suppress(ProcessLookupError):  # anything of that group still there
            os.killpg(head.pid, signal.SIGKILL)
        shutil.rmtree(temp, ignore_errors=True)


def client_server_logs(temp: Path) -> str:
    """The head's Ray Client server logs, for a failure's message (Ray says only that
    the server "failed", and the folder is gone once the test ends)."""
    logs = sorted(temp.glob("session_*/logs/ray_client_server*"))
    return "".join(f"\n--- {log.name}\n{log.read_text(errors='replace')[-1500:]}" for log in logs)


def test_a_ray_cluster_gives_the_verdicts_of_one_process(
    corpus: Corpus, http: Server, cluster: tuple[str, dict[str, str], Path]
) -> None:
    address, env, temp = cluster
    over_http = f"{http.url}/{corpus.directory.name}/{Path(corpus.files[2]).name}"
    as_file_url = f"file://{corpus.files[3]}"
    inputs = [*corpus.files[:2], over_http, as_file_url, *corpus.files[4:]]
    local = cli("replay", *inputs, *options(corpus))
    done = subprocess.run(
        [str(BIN / "aeroexec"), "replay", *inputs, *options(corpus), "--executor", address],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.stdout == local[1], done.stderr[-2000:] + client_server_logs(temp)
    assert done.returncode == local[0] == 2  # the corpus's planted broken files
    assert [r["recording"] for r in rows(done.stdout)] == inputs
    assert "Traceback" not in done.stderr
