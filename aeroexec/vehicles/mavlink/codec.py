"""Turning bytes into MAVLink messages and messages into recordable dictionaries.

This is the one decoding path of aeroexec's MAVLink side: the live link feeds every UDP
datagram through `Decoder.feed`, `aeroexec.mavlink.tlog` feeds a telemetry log's records
through it, and `packet_record` is what lands in the recording (`mavlink/rx`,
`mavlink/tx`). pymavlink does the parsing (CRC, CRC_EXTRA, MAVLink 1 and 2, signature
checks); this module makes its failure modes into counted rejections, one datagram at a
time, so garbage can never raise, stall the parser or swallow the next good packet.
"""

from __future__ import annotations

import base64
import hashlib
import math
import string
import types
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink

MAVLinkMessage = mavlink.MAVLink_message


@dataclass(frozen=True, slots=True)
class Rejected:
    """Bytes that were not a usable MAVLink packet, and why."""

    #: "bad_crc", "bad_signature", "bad_prefix", "truncated", "malformed", "unknown_message"
    #: (and, from the link, "foreign_address")
    reason: str
    raw: bytes
    detail: str = ""


def signing_key(text: str) -> bytes:
    """The 32-byte MAVLink 2 secret key for `--signing-key`: 64 hex digits are the key
    itself; anything else is a passphrase, hashed with SHA-256 (as MAVProxy does)."""
    cleaned = text.strip()
    if len(cleaned) == 64 and all(c in string.hexdigits for c in cleaned):
        return bytes.fromhex(cleaned)
    if not cleaned:
        raise ValueError("the signing key is empty")
    return hashlib.sha256(cleaned.encode("utf-8")).digest()


def new_codec(system: int, component: int, key: bytes | None = None) -> Any:
    """A pymavlink `MAVLink` object that never raises on bad input (robust parsing);
    with `key`, it signs what it sends and rejects unsigned or wrongly signed packets."""
    mav = mavlink.MAVLink(None, srcSystem=system, srcComponent=component)
    mav.robust_parsing = True
    if key is not None:
        # pymavlink's own setup (timestamp from its 2015 epoch, link id 0); it only
        # touches `.mav`, so it runs on a holder of our codec.
        from pymavlink import mavutil

        holder = types.SimpleNamespace(mav=mav)
        mavutil.mavfile.setup_signing(
            holder, key, sign_outgoing=True, allow_unsigned_callback=None, link_id=0
        )
    return mav


def _classify(detail: str) -> str:
    if "CRC" in detail:
        return "bad_crc"
    if "signature" in detail:
        return "bad_signature"
    if "prefix" in detail:
        return "bad_prefix"
    return "malformed"


class Decoder:
    """Decodes whole datagrams (or tlog records) with `feed`: each call starts from a
    clean parser, so a fragment left by one datagram never glues onto the next. A byte
    stream (TCP, serial) goes through `feed_stream`, which keeps an incomplete packet for
    the next call; `reset` forgets it (a new connection)."""

    def __init__(self, mav: Any) -> None:
        self.mav = mav

    def feed(self, data: bytes) -> tuple[list[MAVLinkMessage], list[Rejected]]:
        messages, rejected = self._parse(data)
        leftover = self.mav.buf_len()
        if leftover > 0:
            tail = bytes(self.mav.buf[self.mav.buf_index :])
            rejected.append(
                Rejected("truncated", tail, f"{leftover} bytes of an incomplete packet")
            )
        self.reset()
        return messages, rejected

    def feed_stream(self, data: bytes) -> tuple[list[MAVLinkMessage], list[Rejected]]:
        return self._parse(data)

    def _parse(self, data: bytes) -> tuple[list[MAVLinkMessage], list[Rejected]]:
        messages: list[MAVLinkMessage] = []
        rejected: list[Rejected] = []
        try:
            parsed = self.mav.parse_buffer(data) or []
        except Exception as exc:  # pymavlink bug or exotic input: count it, never raise
            self.reset()
            return [], [Rejected("malformed", bytes(data), f"{type(exc).__name__}: {exc}")]
        for msg in parsed:
            if msg.get_type() == "BAD_DATA":
                detail = str(getattr(msg, "reason", ""))
                rejected.append(Rejected(_classify(detail), bytes(msg.get_msgbuf()), detail))
            elif isinstance(msg, mavlink.MAVLink_unknown):
                # pymavlink returns ids outside the dialect before checking the CRC (it
                # has no CRC_EXTRA for them): unverifiable, so never trusted. Random
                # bytes decode this way more often than anything else.
                detail = f"{msg.get_type()}: message id not in the dialect"
                rejected.append(Rejected("unknown_message", bytes(msg.get_msgbuf()), detail))
            else:
                messages.append(msg)
        return messages, rejected

    def reset(self) -> None:
        self.mav.buf = bytearray()
        self.mav.buf_index = 0
        self.mav.expected_length = mavlink.HEADER_LEN_V1 + 2


def json_safe(value: Any) -> Any:
    """A MAVLink field value as JSON: NaN and infinities become strings, bytes base64."""
    if isinstance(value, float):
        if math.isnan(value):
            return "NaN"
        if math.isinf(value):
            return "Infinity" if value > 0 else "-Infinity"
        return value
    if isinstance(value, (bytes, bytearray)):
        return base64.b64encode(bytes(value)).decode("ascii")
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if value is None or isinstance(value, (bool, int, str)):
        return value
    return str(value)


def message_fields(msg: MAVLinkMessage) -> dict[str, Any]:
    """The message's fields (pymavlink's `to_dict()` without its type key), JSON-safe."""
    fields = msg.to_dict()
    fields.pop("mavpackettype", None)
    return {name: json_safe(value) for name, value in fields.items()}


def packet_record(msg: MAVLinkMessage) -> dict[str, Any]:
    """What the recording keeps of one packet, sent or received."""
    header = msg.get_header()
    return {
        "type": msg.get_type(),
        "raw": base64.b64encode(bytes(msg.get_msgbuf())).decode("ascii"),
        "fields": message_fields(msg),
        "system": header.srcSystem,
        "component": header.srcComponent,
        "seq": header.seq,
        "signed": bool(header.incompat_flags & mavlink.MAVLINK_IFLAG_SIGNED),
    }


def enum_name(enum: str, value: int, prefix: str = "") -> str:
    """`MAV_RESULT` 1 -> "TEMPORARILY_REJECTED" (with prefix "MAV_RESULT_" stripped)."""
    entry = mavlink.enums.get(enum, {}).get(value)
    if entry is None:
        return f"{enum}({value})"
    name = str(entry.name)
    return name[len(prefix) :] if prefix and name.startswith(prefix) else name


def command_name(command: int) -> str:
    return enum_name("MAV_CMD", command)


def result_name(result: int) -> str:
    return enum_name("MAV_RESULT", result, "MAV_RESULT_")


def command_number(name: str) -> int:
    """`"MAV_CMD_NAV_TAKEOFF"` or `"NAV_TAKEOFF"` (any case) -> 22; ValueError if unknown."""
    wanted = name.strip().upper()
    if not wanted.startswith("MAV_CMD_"):
        wanted = "MAV_CMD_" + wanted
    for number, entry in mavlink.enums["MAV_CMD"].items():
        if entry.name == wanted:
            return int(number)
    raise ValueError(f"unknown MAVLink command '{name}'")


Tap = Callable[[str, Any], None]
