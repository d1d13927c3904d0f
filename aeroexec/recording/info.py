"""`aeroexec info`: what a recording holds, in one streaming pass.

Counts per channel, time span, metadata, attachments, completeness, and, for aeroexec
recordings, every behavior activation with its outcome (from `activate_behavior` calls
and `behavior_event` messages, matched by activation uid). Works on foreign MCAP files
too (counts only) and on incomplete files (up to where reading stopped).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Any

from aeroexec.recording.damage import Damage
from aeroexec.recording.reader import ChannelInfo, RawMessage, RecordedAttachment, Recording
from aeroexec.recording.schemas import CODE_METADATA_NAME as CODE_RECORD
from aeroexec.recording.schemas import MESSAGE_ENCODING

#: The metadata record `aeroexec recover` adds to a copy of a damaged file.
RECOVER_METADATA_NAME = "aeroexec_recover"

_NS = 1_000_000_000


@dataclass(frozen=True, slots=True)
class ChannelSummary:
    id: int
    topic: str
    message_encoding: str
    schema_name: str
    messages: int


@dataclass(frozen=True, slots=True)
class BehaviorRun:
    """One activation request and what became of it."""

    behavior: str
    requested_ns: int | None
    accepted: bool
    uid: int | None = None
    error: str = ""
    outcome: str | None = None  # the end event's code; None while still active
    ended_ns: int | None = None
    detail: str = ""

    def as_dict(self) -> dict[str, Any]:
        return {
            "behavior": self.behavior,
            "uid": self.uid,
            "requested_s": _seconds(self.requested_ns),
            "accepted": self.accepted,
            "error": self.error,
            "outcome": self.outcome,
            "ended_s": _seconds(self.ended_ns),
            "detail": self.detail,
        }


@dataclass(frozen=True, slots=True)
class InfoReport:
    file: str
    profile: str
    library: str
    complete: bool
    problem: str | None
    messages: int
    channels: tuple[ChannelSummary, ...]
    start_ns: int | None
    end_ns: int | None
    metadata: dict[str, dict[str, str]]
    attachments: tuple[tuple[str, str, int], ...]
    behaviors: tuple[BehaviorRun, ...]
    notes: tuple[str, ...] = field(default=())
    #: Damaged regions stepped over (zero-filled, garbage, CRC mismatches).
    damages: tuple[Damage, ...] = ()
    #: What the file's statistics promise (None: no summary), and how many were read.
    expected_messages: int | None = None
    #: Why reading stopped before the footer (None: the footer was read).
    cut: str | None = None

    @property
    def duration_ns(self) -> int:
        if self.start_ns is None or self.end_ns is None:
            return 0
        return self.end_ns - self.start_ns

    def topic_counts(self) -> dict[str, int]:
        out: dict[str, int] = {}
        for channel in self.channels:
            out[channel.topic] = out.get(channel.topic, 0) + channel.messages
        return out

    def as_dict(self) -> dict[str, Any]:
        return {
            "file": self.file,
            "profile": self.profile,
            "library": self.library,
            "complete": self.complete,
            "problem": self.problem,
            "messages": self.messages,
            "channels": self.topic_counts(),
            "channel_details": [
                {
                    "id": c.id,
                    "topic": c.topic,
                    "message_encoding": c.message_encoding,
                    "schema": c.schema_name,
                    "messages": c.messages,
                }
                for c in self.channels
            ],
            "start_ns": self.start_ns,
            "end_ns": self.end_ns,
            "duration_s": self.duration_ns / _NS,
            "metadata": self.metadata,
            "attachments": [
                {"name": n, "media_type": m, "bytes": size} for n, m, size in self.attachments
            ],
            "behaviors": [b.as_dict() for b in self.behaviors],
            "notes": list(self.notes),
            "damages": [d.as_dict() for d in self.damages],
            "expected_messages": self.expected_messages,
        }

    def to_json(self) -> str:
        return json.dumps(self.as_dict(), indent=2)

    def to_text(self) -> str:
        lines = [
            f"file:        {self.file}",
            f"profile:     {self.profile or '(none)'}  library: {self.library or '(none)'}",
        ]
        if self.complete:
            lines.append("complete:    yes")
        elif self.damages:
            regions = f"{len(self.damages)} damaged region{'s' if len(self.damages) > 1 else ''}"
            if self.expected_messages is not None:
                regions += f", {self.messages} of the {self.expected_messages} messages read"
            if self.cut:
                regions += f"; {self.cut}"
            lines.append(f"complete:    NO: {regions} (try `aeroexec recover`)")
            lines.extend(f"damage:      {d.describe()}" for d in self.damages)
        else:
            lines.append(f"complete:    NO: {self.problem} (try `aeroexec recover`)")
        span = ""
        if self.start_ns is not None and self.end_ns is not None:
            span = f" (log time {self.start_ns / _NS:.3f} .. {self.end_ns / _NS:.3f} s)"
        lines.append(f"duration:    {self.duration_ns / _NS:.3f} s{span}")
        lines.append(f"messages:    {self.messages} on {len(self.channels)} channels")
        for name, values in self.metadata.items():
            if name == CODE_RECORD:
                continue
            pairs = " ".join(f"{k}={v}" for k, v in values.items())
            lines.append(f"metadata:    {name}: {pairs}")
        code = self.metadata.get(CODE_RECORD, {})
        if code:
            # Which code implemented each behavior (module:Class and its source hash).
            width = max(len(name) for name in code)
            lines.append("code:")
            lines.extend(f"  {name:<{width}}  {entry}" for name, entry in code.items())
        for name, media, size in self.attachments:
            lines.append(f"attachment:  {name} ({media}, {size} bytes)")
        if self.channels:
            width = max(len(c.topic) for c in self.channels)
            lines.append("channels:")
            for c in self.channels:
                schema = c.schema_name or "(no schema)"
                lines.append(
                    f"  {c.messages:>8}  {c.topic:<{width}}  {c.message_encoding or '-'} {schema}"
                )
        if self.behaviors:
            lines.append("behaviors:")
            for run in self.behaviors:
                lines.append("  " + _run_line(run))
        for note in self.notes:
            lines.append(f"note:        {note}")
        return "\n".join(lines)


def _seconds(ns: int | None) -> float | None:
    return None if ns is None else ns / _NS


def _run_line(run: BehaviorRun) -> str:
    at = f"{run.requested_ns / _NS:9.3f} s" if run.requested_ns is not None else "        ? s"
    who = run.behavior + (f" #{run.uid}" if run.uid is not None else "")
    if not run.accepted:
        return f"{at}  {who}: rejected: {run.error}"
    if run.outcome is None:
        return f"{at}  {who}: still active"
    end = f" at {run.ended_ns / _NS:.3f} s" if run.ended_ns is not None else ""
    detail = f" ({run.detail})" if run.detail else ""
    return f"{at}  {who}: {run.outcome}{end}{detail}"


class _Outcomes:
    """Matches activation calls and end events by uid, in file order."""

    def __init__(self) -> None:
        self._runs: list[dict[str, Any]] = []
        self._by_uid: dict[int, dict[str, Any]] = {}

    def activation(self, data: dict[str, Any], log_time_ns: int) -> None:
        request = data.get("request") or {}
        response = data.get("response") or {}
        ok = bool(response.get("ok"))
        uid = response.get("uid") if ok else None
        run: dict[str, Any] = {
            "behavior": str(request.get("behavior", "?")),
            "requested_ns": log_time_ns,
            "accepted": ok,
            "uid": uid if isinstance(uid, int) else None,
            "error": str(response.get("error", "")),
        }
        early = self._by_uid.get(run["uid"]) if run["uid"] is not None else None
        if early is not None and early["requested_ns"] is None:
            # A behavior that fails in on_start ends inside its own activation call, so
            # its event is written before the (completed) call: join the two.
            early.update(run)
            return
        self._runs.append(run)
        if run["uid"] is not None:
            self._by_uid[run["uid"]] = run

    def event(self, data: dict[str, Any], log_time_ns: int) -> None:
        uid = data.get("uid")
        run = self._by_uid.get(uid) if isinstance(uid, int) else None
        if run is None:  # an activation the file does not hold (cut, or not recorded)
            run = {
                "behavior": str(data.get("name", "?")),
                "requested_ns": None,
                "accepted": True,
                "uid": uid if isinstance(uid, int) else None,
            }
            self._runs.append(run)
            if run["uid"] is not None:
                self._by_uid[run["uid"]] = run
        run["outcome"] = str(data.get("code", "?"))
        run["ended_ns"] = log_time_ns
        run["detail"] = str(data.get("detail", ""))

    def runs(self) -> tuple[BehaviorRun, ...]:
        return tuple(BehaviorRun(**run) for run in self._runs)


def _interesting(channel: ChannelInfo) -> str | None:
    if channel.message_encoding != MESSAGE_ENCODING:
        return None
    if channel.topic.endswith("/activate_behavior"):
        return "activation"
    if channel.topic.endswith("/behavior_event"):
        return "event"
    return None


def recording_info(path: str | os.PathLike[str]) -> InfoReport:
    """One streaming pass over `path` (`RecordingError` if it cannot be read at all)."""
    recording = Recording(path)
    channels: dict[int, ChannelInfo] = {}
    counts: dict[int, int] = {}
    kinds: dict[int, str | None] = {}
    metadata: dict[str, dict[str, str]] = {}
    attachments: list[tuple[str, str, int]] = []
    outcomes = _Outcomes()
    start: int | None = None
    end: int | None = None
    undecodable = 0
    aeroexec = recording.is_aeroexec
    for item in recording.items():
        if isinstance(item, RawMessage):
            cid = item.channel.id
            counts[cid] = counts.get(cid, 0) + 1
            t = item.log_time_ns
            start = t if start is None or t < start else start
            end = t if end is None or t > end else end
            kind = kinds.get(cid)
            if kind is not None:
                try:
                    data = json.loads(item.data)
                except ValueError:
                    undecodable += 1
                    continue
                if not isinstance(data, dict):
                    undecodable += 1
                elif kind == "activation":
                    outcomes.activation(data, t)
                else:
                    outcomes.event(data, t)
        elif isinstance(item, ChannelInfo):
            channels[item.id] = item
            counts.setdefault(item.id, 0)
            kinds[item.id] = _interesting(item) if aeroexec else None
        elif isinstance(item, RecordedAttachment):
            attachments.append((item.name, item.media_type, len(item.data)))
        else:
            metadata[item.name] = dict(item.metadata)
    scan_end = recording.end
    notes = list(recording.notes)
    if undecodable:
        notes.append(f"{undecodable} behavior message(s) were not valid JSON")
    recovered = metadata.get(RECOVER_METADATA_NAME)
    if recovered is not None and recovered.get("damaged_regions", "0") != "0":
        copied, expected = recovered.get("messages_copied"), recovered.get("messages_expected")
        of = f" ({copied} of {expected} messages)" if copied and expected else ""
        notes.append(
            f"recovered from a damaged {recovered.get('source', 'recording')}{of}: "
            f"not the whole session (metadata {RECOVER_METADATA_NAME} says what is missing)"
        )
    if not aeroexec:
        notes.append(
            f"profile {recording.profile or '(none)'!r} is not aeroexec: counts only, "
            "no behavior outcomes"
        )
    return InfoReport(
        file=recording.name,
        profile=recording.profile,
        library=recording.library,
        complete=scan_end.complete,
        problem=scan_end.problem,
        messages=sum(counts.values()),
        channels=tuple(
            ChannelSummary(c.id, c.topic, c.message_encoding, c.schema_name, counts[c.id])
            for c in channels.values()
        ),
        start_ns=start,
        end_ns=end,
        metadata=metadata,
        attachments=tuple(attachments),
        behaviors=outcomes.runs(),
        notes=tuple(notes),
        damages=scan_end.damages,
        expected_messages=scan_end.expected_messages,
        cut=scan_end.cut,
    )
