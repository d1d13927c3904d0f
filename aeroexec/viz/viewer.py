"""Finding and starting the Rerun viewer on a written `.rrd` file.

The viewer is the `rerun` binary that ships with rerun-sdk (the `rerun_cli` package), or
a `rerun` on PATH. The native viewer needs a display (X11 or Wayland on Linux) and is left
running on its own (a window the user closes). The web viewer (`--web`) needs none: it
serves the file over HTTP for as long as aeroexec runs.

**The web viewer ends with aeroexec.** `serve_web` starts it, prints where to open it,
and waits; whatever ends aeroexec's wait — Ctrl-C, SIGTERM, SIGHUP (as `Interrupted`
at its safe points), an error — stops the viewer before aeroexec exits. On Linux the
viewer also gets SIGTERM from the kernel if aeroexec dies without a chance to stop it
(SIGKILL): it is started through a two-line shim that sets `PR_SET_PDEATHSIG` and then
execs the viewer.

**Only this machine by default.** The web viewer and its data server listen on
127.0.0.1 unless the caller allows every interface (`--allow-remote`). The page's port
is the caller's (`--port`, default 9090); the data server takes a free port, so two
views never collide on it.
"""

from __future__ import annotations

import importlib.util
import os
import queue
import re
import shutil
import subprocess
import sys
import threading
from collections.abc import Callable, Mapping
from pathlib import Path

from aeroexec import interrupts
from aeroexec.errors import ViewerError

LOOPBACK = "127.0.0.1"
ALL_INTERFACES = "0.0.0.0"
DEFAULT_WEB_PORT = 9090
#: How long the web viewer may take to say where it serves (s).
START_TIMEOUT_S = 30.0
#: How long a stopped viewer gets to end before it is killed (s).
STOP_TIMEOUT_S = 5.0
_POLL_S = 0.1
_URL = re.compile(r"connect at (\S+)")
_ANSI = re.compile(r"\x1b\[[0-9;]*m")

#: Run in a fresh interpreter between aeroexec and the viewer: ask the kernel for SIGTERM
#: when the parent dies (kept across exec), give up if it already has, exec the viewer.
_DIE_WITH_PARENT = (
    "import ctypes, os, sys\n"
    "ctypes.CDLL(None).prctl(1, 15)\n"  # PR_SET_PDEATHSIG, SIGTERM
    "os.getppid() == int(sys.argv[1]) or sys.exit(0)\n"
    "os.execv(sys.argv[2], sys.argv[2:])\n"
)


def viewer_binary() -> Path | None:
    """The rerun viewer executable, or None when there is none."""
    spec = importlib.util.find_spec("rerun_cli")
    if spec is not None and spec.origin:
        folder = Path(spec.origin).parent
        suffix = ".exe" if sys.platform.startswith("win") else ""
        candidates = [folder / f"rerun{suffix}"]
        if sys.platform == "darwin":
            candidates.insert(0, folder / "Rerun.app" / "Contents" / "MacOS" / "Rerun")
        for candidate in candidates:
            if candidate.is_file() and os.access(candidate, os.X_OK):
                return candidate
    found = shutil.which("rerun")
    return Path(found) if found else None


def has_display(environ: Mapping[str, str] | None = None, platform: str | None = None) -> bool:
    """Whether a native window can open: always on macOS and Windows, on other systems
    when DISPLAY or WAYLAND_DISPLAY is set."""
    env = os.environ if environ is None else environ
    system = sys.platform if platform is None else platform
    if system == "darwin" or system.startswith("win"):
        return True
    return bool(env.get("DISPLAY") or env.get("WAYLAND_DISPLAY"))


def cannot_spawn(
    *, web: bool = False, environ: Mapping[str, str] | None = None, binary: Path | None = None
) -> str | None:
    """Why the viewer cannot be started (None when it can)."""
    if (binary or viewer_binary()) is None:
        return "no Rerun viewer found (the `rerun` binary of rerun-sdk)"
    if not web and not has_display(environ):
        return "no display (DISPLAY and WAYLAND_DISPLAY are unset); try --web"
    return None


def viewer_command(
    rrd: Path,
    *,
    web: bool = False,
    binary: Path | None = None,
    bind: str = LOOPBACK,
    port: int = DEFAULT_WEB_PORT,
) -> list[str]:
    exe = binary or viewer_binary()
    if exe is None:
        raise FileNotFoundError("no Rerun viewer found")
    command = [str(exe)]
    if web:
        # --port 0: the data server on a free port (the page is told where).
        command += ["--web-viewer", "--bind", bind, "--web-viewer-port", str(port), "--port", "0"]
    command.append(str(rrd))
    return command


def open_viewer(rrd: Path) -> None:
    """Start the native viewer on `rrd`, detached: the command returns at once and the
    window stays until the user closes it."""
    subprocess.Popen(  # our own argv, no shell
        viewer_command(rrd),
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )


def _bound_to_parent(command: list[str]) -> list[str]:
    if not sys.platform.startswith("linux"):
        return command
    return [sys.executable, "-I", "-S", "-c", _DIE_WITH_PARENT, str(os.getpid()), *command]


def _read_lines(stream: object, lines: queue.Queue[str | None]) -> None:
    for line in stream:  # type: ignore[attr-defined]
        lines.put(_ANSI.sub("", line).strip())
    lines.put(None)


def serve_web(
    rrd: Path,
    *,
    bind: str = LOOPBACK,
    port: int = DEFAULT_WEB_PORT,
    on_ready: Callable[[str, int], None] | None = None,
) -> int:
    """Serve the web viewer on `rrd` until it ends or aeroexec is stopped, and stop it
    then in any case. `on_ready(url, pid)` is told where to open it (and the viewer's
    process id) once it serves. Returns the viewer's exit status; `ViewerError` when it
    cannot serve (the port is taken, ...); `Interrupted` (with a note) when a signal
    stopped aeroexec."""
    command = _bound_to_parent(viewer_command(rrd, web=True, bind=bind, port=port))
    try:
        process = subprocess.Popen(  # our own argv, no shell
            command,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            errors="replace",
        )
    except OSError as exc:
        raise ViewerError(f"cannot start the Rerun viewer: {exc.strerror or exc}") from None
    lines: queue.Queue[str | None] = queue.Queue()
    reader = threading.Thread(target=_read_lines, args=(process.stdout, lines), daemon=True)
    reader.start()
    try:
        url = _wait_until_serving(process, lines, bind, port)
        if on_ready is not None:
            on_ready(url, process.pid)
        while True:
            interrupts.check()
            try:
                status = process.wait(_POLL_S)
            except subprocess.TimeoutExpired:
                continue
            if -status in interrupts.HANDLED:
                # Ctrl-C reaches the whole process group: the viewer may be gone before
                # our own handler has noted the signal. Either way, it is a stop by
                # signal N (128+N), not a viewer that failed.
                interrupts.check()
                raise interrupts.Interrupted(-status)
            return status
    except interrupts.Interrupted as exc:
        exc.notes.append("web viewer stopped")
        raise
    finally:
        _stop(process, reader)


def _wait_until_serving(
    process: subprocess.Popen[str], lines: queue.Queue[str | None], bind: str, port: int
) -> str:
    seen: list[str] = []
    waited = 0.0
    while waited < START_TIMEOUT_S:
        interrupts.check()
        try:
            line = lines.get(timeout=_POLL_S)
        except queue.Empty:
            waited += _POLL_S
            continue
        if line is None:  # the viewer ended before serving
            process.wait()
            raise ViewerError(
                f"the Rerun web viewer could not serve on {bind}:{port}: {_why(seen)}"
            )
        seen.append(line)
        found = _URL.search(line)
        if found:
            # Keep reading (and dropping) what it prints, so its output never blocks it.
            threading.Thread(target=_drain, args=(lines,), daemon=True).start()
            return found.group(1)
    raise ViewerError(f"the Rerun web viewer did not start serving within {START_TIMEOUT_S:g} s")


def _drain(lines: queue.Queue[str | None]) -> None:
    while lines.get() is not None:
        pass


def _why(seen: list[str]) -> str:
    errors = [line for line in seen if line.startswith("Error:")]
    text = errors[-1].removeprefix("Error:").strip() if errors else (seen[-1] if seen else "")
    return text or "it ended without saying why"


def _stop(process: subprocess.Popen[str], reader: threading.Thread) -> None:
    if process.poll() is None:
        process.terminate()
        try:
            process.wait(STOP_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
    reader.join(STOP_TIMEOUT_S)  # the pipe ends with the process
    if process.stdout is not None and not reader.is_alive():
        process.stdout.close()
