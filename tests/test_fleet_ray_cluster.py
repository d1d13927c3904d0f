"""docs/fleet.md's two-node cluster, run as the page writes it (issue 23).

The commands are read from the page's "A two-node cluster on one machine" block, so the
page and this test cannot drift: the export, the token, `ray start --head` and the
worker's `ray start` (each in its own process group, as in its own terminal), then the
replay through Ray Client, which must print what `--jobs 1` prints and exit alike. Only
what would collide with other Rays of a shared machine changes: the two ports (free
ones instead of 6379 and 10001) and Ray's temporary directory; HOME is a fresh
directory, as on a machine where Ray never ran. Then each way of getting the connection
wrong is one line naming its cause, at once: no token mode, a wrong token, a port nobody
listens on.

Slow (a Ray head and a worker start: ~1 min on a loaded two-core machine); skipped only
when Ray is not installed.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from fleet_corpus import Corpus, make_corpus

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "fleet.md"
BIN = Path(sys.executable).parent
START_TIMEOUT_S = 180


@dataclass(frozen=True)
class Recipe:
    environment: dict[str, str]
    token: list[str]
    head: list[str]
    worker: list[str]
    replay: list[str]


def recipe() -> Recipe:
    """The block's commands, comments dropped, each split as a shell would."""
    text = DOC.read_text(encoding="utf-8")
    section = text[text.index("### A two-node cluster on one machine") :]
    block = re.search(r"```sh\n(.*?)```", section, re.S)
    assert block is not None, "docs/fleet.md: the two-node block is gone"
    lines = [shlex.split(line, comments=True) for line in block[1].splitlines()]
    environment: dict[str, str] = {}
    commands = []
    for words in filter(None, lines):
        if words[0] == "export":
            environment.update(w.split("=", 1) for w in words[1:])  # type: ignore[misc]
        else:
            commands.append([w for w in words if w != ">/dev/null"])
    token, head, worker, replay = commands
    assert token[:2] == ["ray", "get-auth-token"] and head[:3] == ["ray", "start", "--head"]
    assert worker[:2] == ["ray", "start"] and replay[:2] == ["aeroexec", "replay"]
    return Recipe(environment, token, head, worker, replay)


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def ported(words: list[str], ports: dict[str, str]) -> list[str]:
    """`words` with the page's ports replaced by this run's, and its programs by this
    venv's (the page runs them from the activated venv)."""
    text = shlex.join(words)
    for page, here in ports.items():
        text = re.sub(rf"(?<=[:=]){page}\b", here, text)
    words = shlex.split(text)
    return [str(BIN / words[0]), *words[1:]]


@dataclass
class Cluster:
    address: str  # ray://127.0.0.1:PORT
    gcs: str  # 127.0.0.1:PORT
    env: dict[str, str]
    replay: list[str]  # the page's replay command, on this run's ports


def _stop(process: subprocess.Popen[bytes]) -> None:
    """As Ctrl-C in its terminal, then what is left of its process group."""
    with contextlib.suppress(ProcessLookupError):
        os.killpg(process.pid, signal.SIGINT)
    with contextlib.suppress(subprocess.TimeoutExpired):
        process.wait(60)
    with contextlib.suppress(ProcessLookupError):
        os.killpg(process.pid, signal.SIGKILL)
    with contextlib.suppress(subprocess.TimeoutExpired):
        process.wait(10)


def _started(log: Path, process: subprocess.Popen[bytes], what: str) -> None:
    deadline = time.monotonic() + START_TIMEOUT_S
    while time.monotonic() < deadline:
        if "Ray runtime started" in log.read_text(errors="replace"):
            return
        if process.poll() is not None:
            break
        time.sleep(0.5)
    tail = log.read_text(errors="replace")[-2000:]
    pytest.fail(f"{what} did not start (exit {process.poll()}):\n{tail}")


def _joined(gcs: str, env: dict[str, str], nodes: int) -> None:
    """Wait until `ray status` counts `nodes` active nodes (its view lags the start)."""
    deadline = time.monotonic() + START_TIMEOUT_S
    status = ""
    while time.monotonic() < deadline:
        status = subprocess.run(
            [str(BIN / "ray"), "status", f"--address={gcs}"],
            env=env,
            capture_output=True,
            text=True,
            timeout=120,
        ).stdout
        active = status.split("Active:", 1)[-1].split("Pending:", 1)[0]
        if len(re.findall(r"^\s*1 node_[0-9a-f]+$", active, re.M)) == nodes:
            return
        time.sleep(2)
    pytest.fail(f"the cluster never had {nodes} nodes:\n{status}")


@pytest.fixture(scope="module")
def cluster(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Cluster]:
    pytest.importorskip("ray", reason="Ray is not installed (pip install 'aeroexec[ray]')")
    if not (BIN / "ray").exists():
        pytest.skip(f"no `ray` command beside {sys.executable}")
    steps = recipe()
    home = tmp_path_factory.mktemp("home")
    temp = tempfile.mkdtemp(prefix="ray2n-")  # short: Ray's socket paths must fit
    env = {k: v for k, v in os.environ.items() if not k.startswith("RAY_")}
    env |= {"HOME": str(home), **steps.environment}
    ports = {"6379": str(free_port()), "10001": str(free_port())}
    token = subprocess.run(ported(steps.token, ports), env=env, capture_output=True, timeout=60)
    assert token.returncode == 0, token.stderr
    assert (home / ".ray" / "auth_token").is_file()
    logs = tmp_path_factory.mktemp("logs")
    nodes: list[subprocess.Popen[bytes]] = []
    try:
        for name, words, extra in (
            ("head", steps.head, [f"--temp-dir={temp}"]),
            ("worker", steps.worker, []),
        ):
            log = logs / f"{name}.log"
            with log.open("wb") as out:
                process = subprocess.Popen(
                    [*ported(words, ports), *extra],
                    env=env,
                    cwd=ROOT,
                    stdout=out,
                    stderr=subprocess.STDOUT,
                    start_new_session=True,  # its own terminal: stopped by its group
                )
            nodes.append(process)
            _started(log, process, f"`ray start` of the {name}")
        _joined(f"127.0.0.1:{ports['6379']}", env, nodes=2)
        yield Cluster(
            f"ray://127.0.0.1:{ports['10001']}",
            f"127.0.0.1:{ports['6379']}",
            env,
            ported(steps.replay, ports),
        )
    finally:
        for process in reversed(nodes):
            _stop(process)
        shutil.rmtree(temp, ignore_errors=True)


@pytest.fixture(scope="module")
def corpus(tmp_path_factory: pytest.TempPathFactory) -> Corpus:
    return make_corpus(tmp_path_factory.mktemp("cluster") / "flights", 10)


def aeroexec(args: list[str], env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(BIN / "aeroexec"), *args],
        env=env,
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_the_pages_two_node_cluster_gives_the_verdict_of_jobs_1(
    cluster: Cluster, corpus: Corpus
) -> None:
    # The page's replay, as written.
    on_ray = aeroexec(cluster.replay[1:], cluster.env)
    at = cluster.replay.index("--executor")
    local = aeroexec([*cluster.replay[1:at], *cluster.replay[at + 2 :], "--jobs", "1"], cluster.env)
    assert (on_ray.returncode, on_ray.stdout) == (local.returncode, local.stdout), on_ray.stderr
    assert on_ray.returncode == 0 and "no differences" in on_ray.stdout
    # A corpus with planted differences and broken files, the same way.
    corpus_args = [
        "replay",
        str(corpus.directory),
        "--catalog",
        str(corpus.narrowed),
        "--mode",
        "open",
        "--check",
        "--format",
        "json",
    ]
    on_ray = aeroexec([*corpus_args, "--executor", cluster.address], cluster.env)
    local = aeroexec([*corpus_args, "--jobs", "1"], cluster.env)
    assert on_ray.stdout == local.stdout and on_ray.returncode == local.returncode == 2
    assert "Traceback" not in on_ray.stderr
    # With --spec, each replay is checked on the node that replayed it.
    checked = [*corpus_args, "--spec", "aeroexec:safety"]
    on_ray = aeroexec([*checked, "--executor", cluster.address], cluster.env)
    local = aeroexec([*checked, "--jobs", "1"], cluster.env)
    assert on_ray.stdout == local.stdout and on_ray.returncode == local.returncode == 2
    assert json.loads(on_ray.stdout)["properties"]["recordings"]


@pytest.mark.parametrize(
    ("change", "says"),
    [
        ({"RAY_AUTH_MODE": None}, "uses Ray's token authentication and this process does not"),
        ({"RAY_AUTH_TOKEN": "0" * 64}, "refused this process's token"),
        ({"port": "closed"}, "nothing answers at 127.0.0.1:"),
    ],
    ids=["no-token-mode", "wrong-token", "no-head"],
)
def test_each_wrong_connection_is_one_line_naming_its_cause_at_once(
    cluster: Cluster, change: dict[str, str | None], says: str
) -> None:
    env = dict(cluster.env)
    address = cluster.address
    for key, value in change.items():
        if key == "port":
            address = f"ray://127.0.0.1:{free_port()}"
        elif value is None:
            env.pop(key, None)
        else:
            env[key] = value
    started = time.monotonic()
    done = aeroexec(
        ["replay", "recordings/", "--executor", address, "--check"],
        env,
    )
    took = time.monotonic() - started
    assert (done.returncode, done.stdout) == (2, ""), done.stderr
    (line,) = done.stderr.splitlines()
    assert line.startswith(f"aeroexec replay: error: cannot reach Ray on {address}: "), line
    assert says in line and line.endswith("(see docs/fleet.md#when-ray-client-cannot-connect)")
    assert took < 25, f"{took:.0f} s: Ray Client's own timeout is ~30 s"


@pytest.mark.parametrize(
    ("ray_file", "message", "cause"),
    [
        (
            "util/client/server/proxier.py",
            "Starting Ray client server failed",
            "exited before serving: its log is ray_client_server_<port>.err",
        ),
        (
            "util/client/server/proxier.py",
            "Proxy failed to Connect to backend",
            "RAY_CLIENT_SERVER_CHECK_CHANNEL_TIMEOUT_S (30 s by default)",
        ),
        ("util/client/worker.py", "ray client connection timeout", "within Ray's retries"),
    ],
)
def test_the_head_proxys_failures_get_their_causes(ray_file: str, message: str, cause: str) -> None:
    """The messages the hints recognize are the installed Ray's own (a Ray that rewords
    them turns this red rather than the hints silent)."""
    ray = pytest.importorskip("ray", reason="Ray is not installed (pip install 'aeroexec[ray]')")
    from aeroexec.replay.ray_client_check import hint

    assert message in (Path(ray.__file__).parent / ray_file).read_text(encoding="utf-8")
    said = hint(f"ConnectionAbortedError: Initialization failure from server:\n{message}.")
    assert said.startswith("; ") and cause in said
    assert said.endswith("(see docs/fleet.md#when-ray-client-cannot-connect)")
    assert hint("some other failure") == ""
