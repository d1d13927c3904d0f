"""The ports a live view listens on: checked before a server takes them, or a free one."""

from __future__ import annotations

import socket

from aeroexec.errors import ViewerError

LOOPBACK = "127.0.0.1"


def check_port_free(host: str, port: int, what: str) -> None:
    """`ViewerError` when `port` cannot be listened on (Rerun's server fails later, and
    only in its log, otherwise)."""
    if port == 0:
        return
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind((host, port))
        except OSError as exc:
            raise ViewerError(
                f"{what} cannot listen on {host}:{port}: {exc.strerror or exc}"
            ) from None


def free_port(host: str = LOOPBACK) -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind((host, 0))
        return int(probe.getsockname()[1])
