"""A MAVLink link: one transport (UDP, TCP or serial), one pymavlink codec, counters, a tap.

Single-threaded and non-blocking: `poll()` returns whatever packets are waiting (or
waits at most `timeout` seconds for the first bytes). Every packet sent and every packet
received from the peer goes to the tap as `("mavlink/tx" | "mavlink/rx", record)`;
bytes that are not a usable packet, and datagrams from anyone but the peer, go to
`mavlink/rejected` (the first `MAX_REJECTED_RECORDS` of them; all are counted).

Datagrams are decoded one at a time by a clean parser (a fragment never glues onto the
next datagram); a stream keeps its parser between reads, since a packet may arrive in
pieces, and starts clean when its connection is reopened. `udpin` learns its peer (see
`transport.UdpTransport`); the other kinds have one peer by construction.
"""

from __future__ import annotations

import base64
import select
import time
from collections import Counter, deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from aeroexec.vehicles.mavlink.codec import (
    Decoder,
    MAVLinkMessage,
    Rejected,
    new_codec,
    packet_record,
)
from aeroexec.vehicles.mavlink.endpoint import Endpoint
from aeroexec.vehicles.mavlink.transport import Address, EventSink, open_transport

Tap = Callable[[str, Any], None]

#: Raw bytes of rejected datagrams are recorded for the first this-many only.
MAX_REJECTED_RECORDS = 1000
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
        on_transport: EventSink | None = None,
        validate: Callable[[MAVLinkMessage], tuple[str, str] | None] | None = None,
    ) -> None:
        """`validate(msg)`: (reason, detail) when a well-formed packet is still unusable
        (non-finite telemetry), else None; such a packet is rejected like a bad one."""
        self.endpoint = endpoint
        self.mav = new_codec(system, component, key)
        self.decoder = Decoder(self.mav)
        self.stats = LinkStats()
        self.tap = tap
        self.corrupt_every = corrupt_every
        self._packets_out = 0
        self._rejected_recorded = 0
        self._on_transport = on_transport
        self._validate = validate
        self.transport = open_transport(
            endpoint, system=system, component=component, on_event=self._transport_event
        )

    @property
    def local_text(self) -> str:
        """`127.0.0.1:14550`, `[::1]:14550`, `/dev/ttyUSB0 at 57600 baud`."""
        return self.transport.local_text

    @property
    def up(self) -> bool:
        """A peer can be reached now (a stream is connected; UDP always)."""
        return self.transport.up

    def _transport_event(self, event: str, detail: str) -> None:
        if event == "closed":
            # A packet cut off by the drop must not glue onto the next connection's bytes.
            self.decoder.reset()
        if self._on_transport is not None:
            self._on_transport(event, detail)

    # -- peer ----------------------------------------------------------------------------
    def lock(self, address: Address) -> None:
        self.transport.lock(address)

    def unlock(self) -> None:
        """Accept a new peer again (udpin only; other links have one peer by design)."""
        self.transport.unlock()

    # -- sending -------------------------------------------------------------------------
    def send(self, msg: MAVLinkMessage) -> bool:
        """Pack, sign if keyed, send to the peer; False (and nothing recorded) if there is
        no peer yet, the connection is down or the transport refused."""
        kind = msg.get_type()
        if not self.transport.up:
            self.stats.unsent[kind] += 1
            return False
        buf = bytearray(msg.pack(self.mav))
        seq = self.mav.seq
        self.mav.seq = (seq + 1) % 256
        self._packets_out += 1
        corrupt = self.corrupt_every > 0 and self._packets_out % self.corrupt_every == 0
        if corrupt:
            signed = msg.get_header().incompat_flags & mavlink.MAVLINK_IFLAG_SIGNED
            buf[-14 if signed else -1] ^= 0xFF  # the CRC's high byte
        if not self.transport.write(bytes(buf)):
            self.stats.unsent[kind] += 1
            return False
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
        """Everything waiting now; if nothing is, wait up to `timeout` s for some bytes."""
        out: list[Received] = []
        transport = self.transport
        if timeout > 0.0:
            fd = transport.fileno()
            if fd is None:  # a stream that is down: nothing can arrive before it reopens
                time.sleep(timeout)
            else:
                try:
                    select.select([fd], [], [], timeout)
                except (OSError, ValueError):
                    return out
        for data, address in transport.read():
            if transport.stream:
                self._decode(self.decoder.feed_stream(data), address, out)
            elif not transport.accepts(address):
                self._reject(Rejected("foreign_address", data, f"from {address[0]}:{address[1]}"))
            else:
                self._decode(self.decoder.feed(data), address, out)
        return out

    def _decode(
        self,
        decoded: tuple[list[MAVLinkMessage], list[Rejected]],
        address: Address,
        out: list[Received],
    ) -> None:
        messages, rejected = decoded
        for bad in rejected:
            self._reject(bad)
        for msg in messages:
            problem = self._validate(msg) if self._validate is not None else None
            if problem is not None:
                self._reject(Rejected(problem[0], bytes(msg.get_msgbuf()), problem[1]))
                continue
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
        self.transport.close()


def _b64(data: bytes) -> str:
    return base64.b64encode(data).decode("ascii")
