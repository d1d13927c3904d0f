"""A real HTTP server over a directory, for the fleet tests' URL inputs (fsspec's HTTP
filesystem reads from it) and for holding one download open, so that a test can kill the
Ray worker stuck in it and watch Ray retry the task.
"""

from __future__ import annotations

import functools
import http.server
import os
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

#: How long a held download waits at most for `release()` (a test that fails early
#: must not leave a thread behind for long).
HOLD_LIMIT_S = 60.0


class Server(http.server.ThreadingHTTPServer):
    daemon_threads = True

    def __init__(self, directory: Path) -> None:
        handler = functools.partial(_Handler, directory=str(directory))
        super().__init__(("127.0.0.1", 0), handler)
        #: URL paths whose first GET is held until `release()`.
        self.hold: set[str] = set()
        self.held = threading.Event()
        self._release = threading.Event()
        self._lock = threading.Lock()

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.server_address[1]}"

    def take_hold(self, path: str) -> bool:
        with self._lock:
            if path not in self.hold:
                return False
            self.hold.discard(path)
        self.held.set()
        self._release.wait(HOLD_LIMIT_S)
        return True

    def release(self) -> None:
        self._release.set()

    def handle_error(self, request: object, client_address: object) -> None:
        """A client gone mid-download (killed, or done after a HEAD) is no news."""


class _Handler(http.server.SimpleHTTPRequestHandler):
    server: Server

    def do_GET(self) -> None:
        if self.server.take_hold(self.path):
            return  # the client was killed meanwhile: nothing to answer
        super().do_GET()

    def log_message(self, format: str, *args: object) -> None:
        """Quiet."""


@contextmanager
def serving(directory: Path) -> Iterator[Server]:
    server = Server(directory)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield server
    finally:
        server.release()
        server.shutdown()
        server.server_close()
        thread.join(5)


def _parent(pid: int) -> int:
    with open(f"/proc/{pid}/stat", encoding="utf-8") as stat:
        return int(stat.read().rsplit(")", 1)[1].split()[1])


def _ours(pid: int) -> bool:
    """Is `pid` a descendant of this process (a Ray worker of the Ray we started)?"""
    me = os.getpid()
    try:
        while pid > 1:
            pid = _parent(pid)
            if pid == me:
                return True
    except OSError:
        return False
    return False


def busy_ray_workers(task_name: str) -> list[int]:
    """Our Ray workers running `task_name` now (Ray titles them `ray::<task name>`)."""
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/cmdline", "rb") as cmdline:
                title = cmdline.read().split(b"\0")[0].decode(errors="replace")
        except OSError:
            continue
        if title.startswith(f"ray::{task_name}") and _ours(int(entry)):
            found.append(int(entry))
    return found


def wait_for(condition: object, timeout: float = 30.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():  # type: ignore[operator]
            return True
        time.sleep(0.05)
    return False
