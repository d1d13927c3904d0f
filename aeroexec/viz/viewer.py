"""Finding and starting the Rerun viewer on a written `.rrd` file.

The viewer is the `rerun` binary that ships with rerun-sdk (the `rerun_cli` package), or
a `rerun` on PATH. The native viewer needs a display (X11 or Wayland on Linux); the web
viewer (`--web`) does not: it serves the file over HTTP until interrupted.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path


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


def viewer_command(rrd: Path, *, web: bool = False, binary: Path | None = None) -> list[str]:
    exe = binary or viewer_binary()
    if exe is None:
        raise FileNotFoundError("no Rerun viewer found")
    command = [str(exe)]
    if web:
        command.append("--web-viewer")
    command.append(str(rrd))
    return command


def open_viewer(rrd: Path, *, web: bool = False) -> int:
    """Start the viewer on `rrd`. The native viewer is detached (the command returns at
    once); the web viewer runs in the foreground until Ctrl-C. Returns the exit status
    (0 for a detached viewer)."""
    command = viewer_command(rrd, web=web)
    if web:
        try:
            return subprocess.call(command)
        except KeyboardInterrupt:
            return 0
    subprocess.Popen(  # our own argv, no shell
        command,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    return 0
