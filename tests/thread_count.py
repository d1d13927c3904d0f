"""A fresh interpreter's thread count, with an environment variable set or unset: the
tests of what `aeroexec` starts threads for (foxglove-sdk's runtime, numpy's BLAS)."""

from __future__ import annotations

import os
import subprocess
import sys


def threads_with(script: str, variable: str, value: str | None) -> tuple[int, str]:
    """Run `script`, which ends printing its thread count and `variable`'s value, with
    `variable` set to `value` (None: unset); those two, as printed."""
    env = {k: v for k, v in os.environ.items() if k != variable}
    if value is not None:
        env[variable] = value
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60, env=env
    )
    assert proc.returncode == 0, proc.stderr
    threads, printed = proc.stdout.split()[-2:]
    return int(threads), printed
