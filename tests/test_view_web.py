"""`aeroexec view --web` with the real Rerun web viewer: it serves on 127.0.0.1 only,
on the port asked for, and its process ends with aeroexec's — on SIGTERM (aeroexec stops
it, says so, exits 143) and on SIGKILL (the kernel's parent-death signal stops it).

Each test runs `aeroexec view` as a subprocess and finds the viewer as its child in
/proc; skipped where there is no /proc or no Rerun viewer binary.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path

import pytest

from aeroexec.mission import APPENDIX_C, SessionConfig, simulate
from aeroexec.viz.viewer import viewer_binary

pytestmark = [
    pytest.mark.skipif(not Path("/proc/self/task").is_dir(), reason="needs Linux's /proc"),
    pytest.mark.skipif(viewer_binary() is None, reason="no Rerun viewer binary (rerun-sdk)"),
]


@pytest.fixture(scope="module")
def flight(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("web") / "flight.mcap"
    simulate(SessionConfig(mission=APPENDIX_C, record=path))
    return path


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _children(pid: int) -> list[int]:
    out: list[int] = []
    for task in Path(f"/proc/{pid}/task").iterdir():
        out += [int(c) for c in (task / "children").read_text().split()]
    return out


def _alive(pid: int) -> bool:
    """Running (a zombie waiting for a reaper that never comes counts as ended)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except FileNotFoundError:
        return False
    state = next(line for line in status.splitlines() if line.startswith("State:"))
    return "zombie" not in state


def _listening(pid: int) -> set[tuple[str, int]]:
    """(address, port) of the TCP sockets `pid` listens on (IPv4 and IPv6)."""
    inodes = set()
    for fd in Path(f"/proc/{pid}/fd").iterdir():
        try:
            target = fd.readlink().as_posix()
        except OSError:
            continue
        if target.startswith("socket:["):
            inodes.add(target[8:-1])
    found = set()
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        for line in Path(table).read_text().splitlines()[1:]:
            fields = line.split()
            local, state, inode = fields[1], fields[3], fields[9]
            if state == "0A" and inode in inodes:  # LISTEN
                address, port = local.split(":")
                if len(address) == 8:
                    ip = ".".join(str(int(address[i : i + 2], 16)) for i in (6, 4, 2, 0))
                else:
                    ip = "::" if int(address, 16) == 0 else address
                found.add((ip, int(port, 16)))
    return found


class View:
    def __init__(self, flight: Path, *args: str, session: bool = False) -> None:
        # session: a process group of its own, to send it a terminal's Ctrl-C (killpg).
        self.popen = subprocess.Popen(
            [sys.executable, "-m", "aeroexec", "view", str(flight), *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            start_new_session=session,
        )

    def wait_serving(self, timeout: float = 60.0) -> str:
        assert self.popen.stdout is not None
        deadline = time.monotonic() + timeout
        for line in self.popen.stdout:
            if line.startswith("serving the web viewer at "):
                return line.split()[5]
            assert time.monotonic() < deadline, "no 'serving' line"
        raise AssertionError(f"view ended: {self.popen.wait()} {self.popen.stderr.read()}")  # type: ignore[union-attr]

    def viewer(self) -> int:
        (child,) = _children(self.popen.pid)
        return child

    def kill(self) -> None:
        if self.popen.poll() is None:
            self.popen.kill()
            self.popen.wait(10)
        for stream in (self.popen.stdout, self.popen.stderr):
            if stream is not None:
                stream.close()


@pytest.fixture
def views() -> Iterator[list[View]]:
    started: list[View] = []
    yield started
    for view in started:
        view.kill()


def _wait_gone(pid: int, timeout: float = 10.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if not _alive(pid):
            return True
        time.sleep(0.1)
    return False


def test_serves_on_loopback_and_stops_with_aeroexec_on_sigterm(
    flight: Path, tmp_path: Path, views: list[View]
) -> None:
    port = _free_port()
    view = View(flight, "--web", "--port", str(port), "--output", str(tmp_path / "f.rrd"))
    views.append(view)
    url = view.wait_serving()
    assert url.startswith(f"http://127.0.0.1:{port}")
    viewer = view.viewer()
    listening = _listening(viewer)
    assert ("127.0.0.1", port) in listening
    assert {ip for ip, _ in listening} == {"127.0.0.1"}  # the data server too
    with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=10) as page:
        assert page.status == 200
    view.popen.send_signal(signal.SIGTERM)
    assert view.popen.wait(20) == 128 + signal.SIGTERM
    assert view.popen.stderr is not None
    assert view.popen.stderr.read() == "aeroexec view: interrupted by SIGTERM; web viewer stopped\n"
    assert not _alive(viewer)  # stopped and reaped before aeroexec exited


def test_the_viewer_ends_when_aeroexec_is_killed(
    flight: Path, tmp_path: Path, views: list[View]
) -> None:
    view = View(flight, "--web", "--port", "0", "--output", str(tmp_path / "f.rrd"))
    views.append(view)
    view.wait_serving()
    viewer = view.viewer()
    assert _alive(viewer)
    view.popen.kill()  # SIGKILL: aeroexec cannot stop it; the kernel does
    view.popen.wait(10)
    assert _wait_gone(viewer), "the web viewer outlived aeroexec"


def test_ctrl_c_to_the_process_group_is_exit_130_and_one_line(
    flight: Path, tmp_path: Path, views: list[View]
) -> None:
    """A terminal's Ctrl-C reaches aeroexec and the viewer at once: the viewer may end
    first (exit status -2), and that is still a stop by SIGINT, not a failed viewer."""
    view = View(flight, "--web", "--port", "0", "--output", str(tmp_path / "f.rrd"), session=True)
    views.append(view)
    view.wait_serving()
    viewer = view.viewer()
    os.killpg(view.popen.pid, signal.SIGINT)
    assert view.popen.wait(20) == 128 + signal.SIGINT
    assert view.popen.stderr is not None
    assert view.popen.stderr.read() == "aeroexec view: interrupted by SIGINT; web viewer stopped\n"
    assert _wait_gone(viewer)
