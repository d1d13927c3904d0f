"""How bytes reach the autopilot: UDP datagrams, or a byte stream (TCP, serial).

`UdpTransport` is a socket of our own, not pymavlink's `mavudp`, because `mavudp` does
not fit a flight link: its `udpin` binds with SO_REUSEADDR (a second ground station on
the same port would silently share the vehicle's packets), its `recv` drops the
sender's address (datagrams from a stranger cannot be told from the autopilot's) and its
`write` sends to every address that ever sent it a datagram (a stranger spraying
garbage at the port would receive our commands), and it is IPv4 only.

`StreamTransport` drives pymavlink's own TCP and serial classes (`aeroexec.vehicles.
mavlink.streams`). A stream can go away (the autopilot rebooted, a cable was pulled, SITL was
killed): the transport then reopens it, at most every `RETRY_PERIOD` seconds, for as
long as the owner keeps polling; `tcpin` goes back to accepting the next client.

Both are non-blocking: `read()` returns what is waiting now.
"""

from __future__ import annotations

import contextlib
import select
import socket
import time
from collections.abc import Callable
from typing import Any, Protocol

from aeroexec.vehicles.mavlink.endpoint import Endpoint, MavlinkError

Address = tuple[str, int]
#: Told "open" / "closed" (with a detail) when a stream connection comes or goes.
EventSink = Callable[[str, str], None]

MAX_DATAGRAM = 65535
#: Datagrams read per `read()` at most, so a flood cannot keep the executive from running.
MAX_DATAGRAMS_PER_READ = 2000
#: Seconds between attempts to (re)open a stream that is down.
RETRY_PERIOD = 0.5
#: Seconds a TCP connect may take (a loopback refusal is immediate).
CONNECT_TIMEOUT = 1.0


class Transport(Protocol):
    endpoint: Endpoint

    @property
    def stream(self) -> bool: ...

    @property
    def up(self) -> bool:
        """A peer can be reached now (always, for UDP)."""

    @property
    def local_text(self) -> str: ...

    def fileno(self) -> int | None: ...

    def read(self) -> list[tuple[bytes, Address]]: ...

    def write(self, data: bytes) -> bool: ...

    def lock(self, address: Address) -> None: ...

    def unlock(self) -> None: ...

    def accepts(self, address: Address) -> bool: ...

    def close(self) -> None: ...


def open_transport(
    endpoint: Endpoint, *, system: int, component: int, on_event: EventSink | None = None
) -> Transport:
    """The transport for `endpoint`; `MavlinkError` if it cannot be opened at all (a port
    taken, a serial device missing). A TCP server that is not up yet is no error: the
    connection is retried while the owner polls."""
    if endpoint.stream:
        return StreamTransport(endpoint, system=system, component=component, on_event=on_event)
    return UdpTransport(endpoint)


class UdpTransport:
    """`udpin` learns its peer: until `lock(address)` it accepts datagrams from anyone;
    after, only from that address (the vehicle locks onto the sender of the autopilot's
    first heartbeat and unlocks when the link is lost, so a restarted radio can be found
    again). `udpout` has its peer fixed from the start."""

    stream = False
    up = True

    def __init__(self, endpoint: Endpoint) -> None:
        self.endpoint = endpoint
        family = socket.AF_INET6 if ":" in endpoint.host else socket.AF_INET
        self.sock = socket.socket(family, socket.SOCK_DGRAM)
        try:
            self.sock.setblocking(False)
            if endpoint.kind == "udpin":
                # No SO_REUSEADDR: a second ground station on the same port must fail
                # loudly, not silently share the vehicle's packets with the first.
                self.sock.bind(endpoint.address)
                self.peer: Address | None = None
                self.locked = False
            else:
                loopback = "::1" if family == socket.AF_INET6 else "127.0.0.1"
                self.sock.bind((loopback, 0) if endpoint.loopback else ("", 0))
                self.peer = endpoint.address
                self.locked = True
        except OSError as exc:
            self.sock.close()
            raise MavlinkError(f"cannot open {endpoint.url}: {exc.strerror or exc}") from None

    @property
    def local_text(self) -> str:
        """`127.0.0.1:14550` or `[::1]:14550`."""
        host, port = self.sock.getsockname()[:2]
        return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"

    def fileno(self) -> int | None:
        return self.sock.fileno()

    def lock(self, address: Address) -> None:
        if self.endpoint.kind == "udpin":
            self.peer = address
            self.locked = True

    def unlock(self) -> None:
        if self.endpoint.kind == "udpin":
            self.locked = False

    def accepts(self, address: Address) -> bool:
        return not self.locked or address == self.peer

    def read(self) -> list[tuple[bytes, Address]]:
        out: list[tuple[bytes, Address]] = []
        for _ in range(MAX_DATAGRAMS_PER_READ):
            try:
                data, address = self.sock.recvfrom(MAX_DATAGRAM)
            except (BlockingIOError, InterruptedError):
                break
            except OSError:
                # e.g. ECONNREFUSED from an ICMP "port unreachable" for an earlier send.
                continue
            out.append((data, (address[0], address[1])))
        return out

    def write(self, data: bytes) -> bool:
        if self.peer is None:
            return False
        try:
            self.sock.sendto(data, self.peer)
        except OSError:
            return False
        return True

    def close(self) -> None:
        self.sock.close()


class StreamTransport:
    """A TCP connection (either side) or a serial port, through pymavlink's classes."""

    stream = True

    def __init__(
        self,
        endpoint: Endpoint,
        *,
        system: int,
        component: int,
        on_event: EventSink | None = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.endpoint = endpoint
        self._system = system
        self._component = component
        self._on_event = on_event
        self._clock = clock
        self._conn: Any = None
        self._next_attempt = -float("inf")
        #: Why the last attempt to open failed ("" when it did not).
        self.last_error = ""
        #: The address a received chunk is attributed to (streams have one peer).
        self.peer: Address = (endpoint.host or endpoint.device, endpoint.port or endpoint.baud)
        if endpoint.kind in ("tcpin", "serial"):
            # A port that cannot be had now is an input error, not a peer that is late.
            self._open(raise_errors=True)
        else:
            self.reopen()

    # -- connection ----------------------------------------------------------------------
    @property
    def up(self) -> bool:
        if self._conn is None:
            return False
        if self.endpoint.kind == "tcpin":
            return bool(self._conn.has_client)
        return True

    def reopen(self) -> None:
        """Try to (re)open a stream that is down, unless the last try was too recent."""
        if self._conn is not None or self._clock() < self._next_attempt:
            return
        self._open(raise_errors=False)

    def _open(self, *, raise_errors: bool) -> None:
        self._next_attempt = self._clock() + RETRY_PERIOD
        from aeroexec.vehicles.mavlink.streams import open_stream

        try:
            self._conn = open_stream(
                self.endpoint,
                timeout=CONNECT_TIMEOUT,
                system=self._system,
                component=self._component,
            )
        except ImportError as exc:
            raise MavlinkError(f"cannot open {self.endpoint.url}: {exc}") from None
        except (OSError, ValueError) as exc:
            self.last_error = _reason(exc)
            if raise_errors:
                raise MavlinkError(f"cannot open {self.endpoint.url}: {self.last_error}") from None
            return
        self.last_error = ""
        if self.endpoint.kind != "tcpin":
            self._tell("open", "")

    def _drop(self, why: str) -> None:
        conn, kind = self._conn, self.endpoint.kind
        if conn is None:
            return
        if kind == "tcpin":
            conn.drop_client()
        else:
            self._conn = None
            self._next_attempt = self._clock() + RETRY_PERIOD
            # Closing a dead port may fail too; it is gone either way.
            with contextlib.suppress(Exception):
                conn.close()
        self._tell("closed", why)

    def _tell(self, event: str, detail: str) -> None:
        if self._on_event is not None:
            self._on_event(event, detail)

    @property
    def local_text(self) -> str:
        conn = self._conn
        if self.endpoint.kind == "serial":
            return f"{self.endpoint.device} at {self.endpoint.baud} baud"
        sock = None
        if conn is not None:
            sock = conn.listen if self.endpoint.kind == "tcpin" else conn.port
        if sock is None:
            return "not connected"
        host, port = sock.getsockname()[:2]
        return f"{host}:{port}"

    def fileno(self) -> int | None:
        return self._conn.fileno() if self._conn is not None else None

    # -- the peer (one per stream) -------------------------------------------------------
    def lock(self, address: Address) -> None:
        pass

    def unlock(self) -> None:
        pass

    def accepts(self, address: Address) -> bool:
        return True

    # -- data ----------------------------------------------------------------------------
    def read(self) -> list[tuple[bytes, Address]]:
        self.reopen()
        conn = self._conn
        if conn is None:
            return []
        accepting = self.endpoint.kind == "tcpin" and not conn.has_client
        fd = conn.fileno()
        try:
            ready = bool(fd is not None and select.select([fd], [], [], 0.0)[0])
        except (OSError, ValueError):
            ready = False
        if not ready:
            return []
        from aeroexec.vehicles.mavlink.streams import CHUNK

        try:
            data = conn.recv(CHUNK)
        except OSError as exc:  # a reset connection, a serial port that went away
            self._drop(_reason(exc))
            return []
        if accepting:
            if conn.has_client:
                self._tell("open", "client connected")
            return [(bytes(data), self.peer)] if data else []
        if not data or conn.closed:
            # Readable but nothing to read: the peer closed the connection.
            self._drop("closed by the peer")
            return []
        return [(bytes(data), self.peer)]

    def write(self, data: bytes) -> bool:
        self.reopen()
        conn = self._conn
        if conn is None or not self.up:
            return False
        conn.write(data)
        if conn.closed:
            self._drop("closed by the peer")
            return False
        return True

    def close(self) -> None:
        conn, self._conn = self._conn, None
        if conn is not None:
            if self.endpoint.kind in ("tcp", "tcpin"):
                from aeroexec.vehicles.mavlink.streams import finish

                finish(conn.port)
            conn.close()


def _reason(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror:
        return str(exc.strerror)
    return str(exc) or type(exc).__name__
