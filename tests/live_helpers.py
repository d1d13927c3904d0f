"""What the live-flight tests share: free loopback ports, a mission file, `mavsim` in a
thread, and `python -m aeroexec ...` in a subprocess whose output lines can be waited for."""

from __future__ import annotations

import os
import queue
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from aeroexec.mavlink.sim_peer import MavSim, MavSimConfig


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def free_tcp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def write_mission(tmp_path: Path, body: str) -> Path:
    path = tmp_path / "mission.py"
    path.write_text("import executive_engine_api as api\n\n\ndef runMission():\n" + body)
    return path


@contextmanager
def mavsim_thread(url: str, *, kind: type[MavSim] = MavSim, **overrides: Any) -> Iterator[MavSim]:
    """A MavSim (or the subclass `kind`: an autopilot that misbehaves on purpose)
    serving `url` from a thread (5x speed, 4 Hz heartbeats, EKF ready after 0.5 vehicle
    seconds, unless `overrides` say otherwise)."""
    settings: dict[str, Any] = {"speed_factor": 5.0, "heartbeat_hz": 4.0, "ekf_delay": 0.5}
    settings.update(overrides)
    sim = kind(MavSimConfig(url=url, **settings))
    stop = threading.Event()
    thread = threading.Thread(target=sim.run, args=(stop.is_set,), daemon=True)
    thread.start()
    try:
        yield sim
    finally:
        stop.set()
        thread.join(5)
        sim.close()


class AeroexecProcess:
    """`python -m aeroexec ARGS` in a subprocess; a thread collects its stdout lines, so a
    test can wait for one without blocking forever."""

    #: Default seconds to wait for a line, and for the process to end.
    wait_s = 15.0
    finish_s = 40.0

    def __init__(self, args: list[str]) -> None:
        self.popen = subprocess.Popen(
            [sys.executable, "-m", "aeroexec", *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        self.lines: queue.Queue[str] = queue.Queue()
        self.out: list[str] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.popen.stdout is not None
        for line in self.popen.stdout:
            self.out.append(line)
            self.lines.put(line)

    def wait_for(self, text: str, timeout: float | None = None) -> str:
        deadline = time.monotonic() + (self.wait_s if timeout is None else timeout)
        while (remaining := deadline - time.monotonic()) > 0:
            try:
                line = self.lines.get(timeout=remaining)
            except queue.Empty:
                break
            if text in line:
                return line
        raise AssertionError(f"no line with {text!r}; it printed:\n{''.join(self.out)}")

    def finish(self, timeout: float | None = None) -> tuple[int, str, str]:
        assert self.popen.stderr is not None
        code = self.popen.wait(self.finish_s if timeout is None else timeout)
        err = self.popen.stderr.read()
        self._reader.join(5)
        return code, "".join(self.out), err

    def stop(self) -> None:
        """SIGTERM, then SIGKILL if it has not ended within 10 s."""
        if self.popen.poll() is None:
            self.popen.send_signal(signal.SIGTERM)
            try:
                self.popen.wait(10)
            except subprocess.TimeoutExpired:
                self.popen.kill()
                self.popen.wait(5)

    def kill(self) -> None:
        if self.popen.poll() is None:
            self.popen.kill()
            self.popen.wait(5)
        for stream in (self.popen.stdout, self.popen.stderr):
            if stream is not None:
                stream.close()


@contextmanager
def cpu_loaded() -> Iterator[None]:
    """Every core busy with a spinning process: what must hold under load is tried so."""
    spinners = [
        subprocess.Popen([sys.executable, "-c", "while True: pass"])
        for _ in range(os.cpu_count() or 2)
    ]
    try:
        yield
    finally:
        for spinner in spinners:
            spinner.kill()
            spinner.wait(5)
