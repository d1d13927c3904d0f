"""Reading MAVLink telemetry logs (`.tlog`) through aeroexec's own decoding path.

A tlog, as MAVProxy and Mission Planner write it, is a sequence of records: an 8-byte
big-endian timestamp (µs since 1970) and one MAVLink packet. Each packet goes through
`codec.Decoder.feed`, exactly as a UDP datagram on the live link does.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from aeroexec.vehicles.mavlink.codec import Decoder, MAVLinkMessage, Rejected, new_codec

_V1, _V2 = 0xFE, 0xFD


@dataclass(frozen=True, slots=True)
class TlogRecord:
    time_us: int
    message: MAVLinkMessage | None
    rejected: Rejected | None = None


def _packet_length(data: bytes, start: int) -> int | None:
    """Length of the packet starting at `start`, or None if no packet starts there."""
    if start + 3 > len(data):
        return None
    magic, payload = data[start], data[start + 1]
    if magic == _V1:
        return 6 + payload + 2
    if magic == _V2:
        signed = data[start + 2] & 0x01
        return 10 + payload + 2 + (13 if signed else 0)
    return None


def read_tlog(path: str | Path) -> Iterator[TlogRecord]:
    """Every record of the log, decoded; a record that is no packet is one `Rejected`
    covering the bytes up to the next plausible record."""
    data = Path(path).read_bytes()
    decoder = Decoder(new_codec(255, 0))
    i = 0
    while i + 8 < len(data):
        (time_us,) = struct.unpack_from(">Q", data, i)
        length = _packet_length(data, i + 8)
        if length is None:
            end = _resync(data, i + 1)
            yield TlogRecord(time_us, None, Rejected("bad_prefix", data[i:end]))
            i = end
            continue
        packet = data[i + 8 : i + 8 + length]
        messages, rejected = decoder.feed(packet)
        for msg in messages:
            yield TlogRecord(time_us, msg)
        for bad in rejected:
            yield TlogRecord(time_us, None, bad)
        i += 8 + length


def _resync(data: bytes, start: int) -> int:
    for j in range(start, len(data) - 9):
        if data[j + 8] in (_V1, _V2):
            return j
    return len(data)
