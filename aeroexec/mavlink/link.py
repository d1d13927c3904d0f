"""A MAVLink link over UDP: one socket, one pymavlink codec, counters and a tap.

Single-threaded and non-blocking: `poll()` returns whatever datagrams are waiting (or
waits at most `timeout` seconds for the first one). Every packet sent and every packet
received from the peer goes to the tap as `("mavlink/tx" | "mavlink/rx", record)`;
bytes that are not a usable packet, and datagrams from anyone but the peer, go to
`mavlink/rejected` (the first `MAX_REJECTED_RECORDS` of them; all are counted).

`udpin` learns its peer: until `lock(address)` is called it accepts datagrams from any
address; after, only from that one (the vehicle locks onto the sender of the
autopilot's first heartbeat and unlocks when the link is lost, so a restarted radio or
autopilot can be found again). `udpout` has its peer fixed from the start.
"""

from __future__ import annotations

import base64
import select
import socket
from collections import Counter, deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from aeroexec.mavlink.codec import Decoder, MAVLinkMessage, Rejected, new_codec, packet_record
from aeroexec.mavlink.endpoint import Endpoint, MavlinkError

Address = tuple[str, int]
Tap = Callable[[str, Any], None]

MAX_DATAGRAM = 65535
#: Raw bytes of rejected datagrams are recorded for the first this-many only.
MAX_REJECTED_RECORDS = 1000
#: Datagrams read per `poll()` at most, so a flood cannot keep the executive from running.
MAX_DATAGRAMS_PER_POLL = 2000
#: How many of the latest packets sent are remembered (see `LinkStats.tail`).
TAIL_LENGTH = 1024


@dataclass(frozen=True, slots=True)
class Received:
    msg: MAVLinkMessage
    address: Address


@dataclass
class LinkStats:
    """What went over the link, by message type. `rejected`: bytes that were no usable
    packet or came from a stranger, by reason; `ignored`: good packets the owner did not
    use (another system's, or before the autopilot's first heartbeat), by reason."""

    sent: Counter[str] = field(default_factory=Counter)
    received: Counter[str] = field(default_factory=Counter)
    rejected: Counter[str] = field(default_factory=Counter)
    ignored: Counter[str] = field(default_factory=Counter)
    corrupted: Counter[str] = field(default_factory=Counter)
    unsent: Counter[str] = field(default_factory=Counter)
    #: (seq, type, corrupted) of the latest packets sent, oldest first: with the seq of
    #: the last packet the peer recorded, what was still in flight when it stopped.
    tail: deque[tuple[int, str, bool]] = field(default_factory=lambda: deque(maxlen=TAIL_LENGTH))

    def as_dict(self) -> dict[str, Any]:
        return {
            "sent": dict(sorted(self.sent.items())),
            "received": dict(sorted(self.received.items())),
            "rejected": dict(sorted(self.rejected.items())),
            "ignored": dict(sorted(self.ignored.items())),
            "corrupted": dict(sorted(self.corrupted.items())),
            "unsent": dict(sorted(self.unsent.items())),
            "tail": [list(item) for item in self.tail],
        }

    def summary(self) -> str:
        text = f"{sum(self.received.values())} received, {sum(self.sent.values())} sent"
        for name, counts in (("rejected", self.rejected), ("ignored", self.ignored)):
            if counts:
                reasons = ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))
                text += f", {sum(counts.values())} {name} ({reasons})"
        return text

    def reasons(self) -> str:
        """ "40 bad_prefix, 1 truncated rejected; 1 before_heartbeat ignored" (or "")."""
        parts = []
        for name, counts in (("rejected", self.rejected), ("ignored", self.ignored)):
            if counts:
                items = ", ".join(f"{v} {k}" for k, v in sorted(counts.items()))
                parts.append(f"{items} {name}")
        return "; ".join(parts)


class Link:
    def __init__(
        self,
        endpoint: Endpoint,
        *,
        system: int,
        component: int,
        key: bytes | None = None,
        tap: Tap | None = None,
        corrupt_every: int = 0,
    ) -> None:
        self.endpoint = endpoint
        self.mav = new_codec(system, component, key)
        self.decoder = Decoder(self.mav)
        self.stats = LinkStats()
        self.tap = tap
        self.corrupt_every = corrupt_every
        self._packets_out = 0
        self._rejected_recorded = 0
        family = socket.AF_INET6 if ":" in endpoint.host else socket.AF_INET
        self.sock = socket.socket(family, socket.SOCK_DGRAM)
        try:
            self.sock.setblocking(False)
            if endpoint.direction == "udpin":
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
    def local_address(self) -> Address:
        host, port = self.sock.getsockname()[:2]
        return (host, port)

    @property
    def local_text(self) -> str:
        """`127.0.0.1:14550` or `[::1]:14550`."""
        host, port = self.local_address
        return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"

    # -- peer ----------------------------------------------------------------------------
    def lock(self, address: Address) -> None:
        if self.endpoint.direction == "udpin":
            self.peer = address
            self.locked = True

    def unlock(self) -> None:
        """Accept a new peer again (udpin only; udpout's peer is the endpoint)."""
        if self.endpoint.direction == "udpin":
            self.locked = False

    # -- sending -------------------------------------------------------------------------
    def send(self, msg: MAVLinkMessage) -> bool:
        """Pack, sign if keyed, send to the peer; False (and nothing recorded) if there is
        no peer yet or the socket refused."""
        kind = msg.get_type()
        if self.peer is None:
            self.stats.unsent[kind] += 1
            return False
        buf = bytearray(msg.pack(self.mav))
        seq = self.mav.seq
        self._packets_out += 1
        corrupt = self.corrupt_every > 0 and self._packets_out % self.corrupt_every == 0
        if corrupt:
            signed = msg.get_header().incompat_flags & mavlink.MAVLINK_IFLAG_SIGNED
            buf[-14 if signed else -1] ^= 0xFF  # the CRC's high byte
        try:
            self.sock.sendto(bytes(buf), self.peer)
        except OSError:
            self.stats.unsent[kind] += 1
            return False
        finally:
            self.mav.seq = (seq + 1) % 256
        self.stats.sent[kind] += 1
        self.stats.tail.append((seq, kind, corrupt))
        if corrupt:
            self.stats.corrupted[kind] += 1
        if self.tap is not None:
            record = packet_record(msg)
            if corrupt:
                record["corrupted"] = True
            self.tap("mavlink/tx", record)
        return True

    # -- receiving -----------------------------------------------------------------------
    def poll(self, timeout: float = 0.0) -> list[Received]:
        """Everything waiting now; if nothing is, wait up to `timeout` s for a datagram."""
        out: list[Received] = []
        if timeout > 0.0:
            try:
                ready, _, _ = select.select([self.sock], [], [], timeout)
            except (OSError, ValueError):
                return out
            if not ready:
                return out
        for _ in range(MAX_DATAGRAMS_PER_POLL):
            try:
                data, address = self.sock.recvfrom(MAX_DATAGRAM)
            except (BlockingIOError, InterruptedError):
                break
            except OSError:
                # e.g. ECONNREFUSED from an ICMP "port unreachable" for an earlier send.
                continue
            self._datagram(data, (address[0], address[1]), out)
        return out

    def _datagram(self, data: bytes, address: Address, out: list[Received]) -> None:
        if self.locked and address != self.peer:
            self._reject(Rejected("foreign_address", data, f"from {address[0]}:{address[1]}"))
            return
        messages, rejected = self.decoder.feed(data)
        for bad in rejected:
            self._reject(bad)
        for msg in messages:
            self.stats.received[msg.get_type()] += 1
            out.append(Received(msg, address))

    def record_rx(self, msg: MAVLinkMessage, ignored: str = "") -> None:
        """Hand a received packet to the tap (the owner decides whether it was used)."""
        if self.tap is not None:
            record = packet_record(msg)
            if ignored:
                record["ignored"] = ignored
            self.tap("mavlink/rx", record)

    def _reject(self, bad: Rejected) -> None:
        self.stats.rejected[bad.reason] += 1
        if self.tap is not None and self._rejected_recorded < MAX_REJECTED_RECORDS:
            self._rejected_recorded += 1
            self.tap(
                "mavlink/rejected",
                {"reason": bad.reason, "detail": bad.detail, "raw": _b64(bad.raw)},
            )

    def count_ignored(self, reason: str) -> None:
        self.stats.ignored[reason] += 1

    def close(self) -> None:
        self.sock.close()


def _b64(data: bytes) -> str:
    return base64.b64encode(data).decode("ascii")
