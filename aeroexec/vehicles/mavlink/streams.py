"""pymavlink's own stream connections (`mavutil.mavtcp`, `mavtcpin`, `mavserial`), fitted
to a ground station that must never block, print or die on a dropped connection.

pymavlink opens and drives the sockets and the serial port; the subclasses change only
what a flight link cannot live with:

* `TcpClient` connects once, with a timeout (`mavtcp` retries with `time.sleep` and
  prints "sleeping" between attempts, and a blocking connect to a silent host can hang
  for minutes); the caller retries on its own schedule.
* All three report a connection the peer closed (`closed`) instead of printing "EOF on
  TCP socket" / "Device is dead" to stdout, where the flight's printout goes.
* `TcpServer` goes back to listening when its client hangs up (`mavtcpin` would read
  the dead socket forever and never accept the next client).

Imported only when a TCP or serial link is opened: `mavutil` is a heavy import.
"""

from __future__ import annotations

import contextlib
import select
import socket
import time
from typing import Any

from pymavlink import mavutil

from aeroexec.vehicles.mavlink.endpoint import Endpoint

#: Bytes read per call (a few hundred packets): small enough to keep steps short.
CHUNK = 16384


class TcpClient(mavutil.mavtcp):  # type: ignore[misc]
    closed = False

    def __init__(self, endpoint: Endpoint, timeout: float, system: int, component: int) -> None:
        self._timeout = timeout
        super().__init__(
            f"{endpoint.host}:{endpoint.port}",
            autoreconnect=False,
            source_system=system,
            source_component=component,
            retries=0,
        )

    def do_connect(self) -> None:
        self.port = socket.create_connection(self.destination_addr, timeout=self._timeout)
        self.port.setblocking(False)
        mavutil.set_close_on_exec(self.port.fileno())
        self.port.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def handle_eof(self) -> None:
        self.closed = True

    def handle_disconnect(self) -> None:
        self.closed = True

    def fileno(self) -> int | None:
        return self.port.fileno() if self.port is not None else None


class TcpServer(mavutil.mavtcpin):  # type: ignore[misc]
    closed = False

    def __init__(self, endpoint: Endpoint, system: int, component: int) -> None:
        super().__init__(
            f"{endpoint.host}:{endpoint.port}",
            source_system=system,
            source_component=component,
        )

    @property
    def has_client(self) -> bool:
        return self.port is not None

    def drop_client(self) -> None:
        """Forget a client that hung up and accept the next one."""
        if self.port is not None:
            self.port.close()
            self.port = None
        self.fd = self.listen.fileno()

    def fileno(self) -> int | None:
        return int(self.fd)


class SerialPort(mavutil.mavserial):  # type: ignore[misc]
    closed = False

    def __init__(self, endpoint: Endpoint, system: int, component: int) -> None:
        super().__init__(
            endpoint.device,
            baud=endpoint.baud,
            autoreconnect=False,
            source_system=system,
            source_component=component,
        )

    def write(self, buf: Any) -> int:
        try:
            return int(self.port.write(bytes(buf)))
        except Exception:  # pyserial raises SerialException or OSError: the port is gone
            self.closed = True
            return -1

    def fileno(self) -> int | None:
        return self.fd if isinstance(self.fd, int) else None


#: Seconds `finish` waits for the peer's end of a TCP connection.
FINISH_S = 0.25


def finish(sock: socket.socket | None, wait: float = FINISH_S) -> None:
    """End a TCP connection so the last packets sent are read: FIN after them, then
    what the peer still sends is read (and dropped) until its FIN, at most `wait` s.
    A plain close with unread data in our receive queue sends a reset instead, and a
    reset can make the peer drop what it had not read yet: the last setpoints."""
    if sock is None:
        return
    with contextlib.suppress(OSError):
        sock.shutdown(socket.SHUT_WR)
        deadline = time.monotonic() + wait
        while (left := deadline - time.monotonic()) > 0:
            if not select.select([sock], [], [], left)[0]:
                break
            if not sock.recv(CHUNK):
                break  # the peer's FIN


def open_stream(endpoint: Endpoint, *, timeout: float, system: int, component: int) -> Any:
    """A connected TCP client, a listening TCP server or an open serial port; OSError
    (or pyserial's SerialException, an OSError too) when it cannot be opened."""
    if endpoint.kind == "tcp":
        return TcpClient(endpoint, timeout, system, component)
    if endpoint.kind == "tcpin":
        return TcpServer(endpoint, system, component)
    return SerialPort(endpoint, system, component)
