"""Evaluate a property set over signals: from a recording (offline) or from a session's
bus (online, `monitor.py`), with the same code, so both give the same verdicts.

    props = load_properties(["aeroexec:safety", "spec.yaml"])
    report = check_recording("flight.mcap", props)
    report.violated                       # the verdicts that failed
    for v in report.verdicts:             # one per property, in file order
        v.status, v.robustness, v.interval_s

This is the oracle of what-if replay and fuzzing: `evaluate(props, signals)` over any
`Signals` (a `SignalBuilder` fed by whatever produced the messages).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass

import orjson

from aeroexec.catalog.loader import parse_catalog
from aeroexec.catalog.model import Catalog
from aeroexec.properties.signals import PERIOD_S, SignalBuilder, Signals
from aeroexec.properties.spec import Property, PropertySet
from aeroexec.recording import RawMessage, RecordedAttachment, open_recording
from aeroexec.recording.schemas import SERVICE_CALL

#: The channels (inside the drone's namespace) signals come from: only these are decoded.
TOPICS = frozenset(
    {
        "vehicle/state",
        "list_of_active_behaviors",
        "list_of_active_capabilities",
        "mission/command",
        "behavior_event",
    }
)
SERVICES = frozenset({"activate_behavior", "default_values"})

HELD, VIOLATED, MISSING = "held", "violated", "missing"

#: Log times from this on (2001-09-09) are instants of the wall clock, as a ROS bag's are,
#: not a session's clock (which starts at 0): such a recording is sampled from its first
#: message, so t=0 is where it begins.
ABSOLUTE_NS = 10**18


@dataclass(frozen=True)
class Verdict:
    property: Property
    status: str  # held | violated | missing
    #: The robustness at time 0, RTAMT's definition (None when signals were missing).
    robustness: float | None = None
    #: The first violating interval, first and last sample time in seconds.
    interval_s: tuple[float, float] | None = None
    #: The signals the session could not give, each with why.
    missing: tuple[tuple[str, str], ...] = ()

    @property
    def name(self) -> str:
        return self.property.name

    def message(self) -> str:
        prop = self.property
        what = prop.description or prop.formula.text
        if self.status == VIOLATED:
            assert self.interval_s is not None
            start, end = self.interval_s
            span = f"from {start:.2f} s to {end:.2f} s" if end > start else f"at {start:.2f} s"
            return f"{what}: violated {span} (robustness {_num(self.robustness)})"
        if self.status == MISSING:
            names = "; ".join(f"{name}: {why}" for name, why in self.missing)
            return f"not checked, missing signal {names}"
        return f"holds (robustness {_num(self.robustness)})"


@dataclass(frozen=True)
class CheckReport:
    recording: str
    verdicts: tuple[Verdict, ...]
    duration_s: float

    @property
    def violated(self) -> tuple[Verdict, ...]:
        return tuple(v for v in self.verdicts if v.status == VIOLATED)

    @property
    def failed(self) -> bool:
        """A violated property of severity error (warnings and notes do not fail)."""
        return any(v.property.severity == "error" for v in self.violated)


def evaluate(properties: PropertySet | Iterable[Property], signals: Signals) -> list[Verdict]:
    props = properties.properties if isinstance(properties, PropertySet) else properties
    verdicts = []
    for prop in props:
        columns = {}
        missing = []
        for name in prop.formula.signals:
            column = signals.get(name)
            if column is None:
                missing.append((name, signals.why_missing(name)))
            else:
                columns[name] = column
        if missing or signals.length == 0:
            if not missing:
                missing.append(("*", "the session has no samples"))
            verdicts.append(Verdict(prop, MISSING, missing=tuple(missing)))
            continue
        outcome = prop.formula.evaluate(columns, signals.length)
        if outcome.holds:
            verdicts.append(Verdict(prop, HELD, outcome.robustness))
        else:
            assert outcome.interval is not None
            first, last = outcome.interval
            interval = (round(first * PERIOD_S, 6), round(last * PERIOD_S, 6))
            verdicts.append(Verdict(prop, VIOLATED, outcome.robustness, interval))
    return verdicts


def catalog_of_recording(text: str | None) -> Catalog | None:
    """The recorded catalog (for capability conflicts), or None when absent or unreadable."""
    if text is None:
        return None
    try:
        return parse_catalog(text, "catalog.yaml")
    except Exception:
        return None


def signals_from_recording(path: str | os.PathLike[str]) -> Signals:
    """The signals of a recording, decoding only the channels they come from."""
    recording = open_recording(path)
    builder = SignalBuilder(None)
    wanted: dict[int, tuple[str, bool] | None] = {}
    last_ns = -1
    origin: int | None = None
    # One pass: the recorder writes its attachments (the catalog) before any message.
    for message in recording.items():
        if not isinstance(message, RawMessage):
            if isinstance(message, RecordedAttachment) and message.name == "catalog.yaml":
                catalog = catalog_of_recording(message.text)
                if catalog is not None:
                    builder.use_catalog(catalog.conflicts_of)
            continue
        if origin is None:
            origin = message.log_time_ns if message.log_time_ns >= ABSOLUTE_NS else 0
        t_ns = message.log_time_ns - origin
        channel = message.channel
        kind = wanted.get(channel.id, False)
        if kind is False:
            name = _inside(channel.topic)
            is_call = channel.schema_name == SERVICE_CALL
            use = name in SERVICES if is_call else name in TOPICS
            kind = wanted[channel.id] = (name, is_call) if use else None
        if kind is None:
            last_ns = max(last_ns, t_ns)
            continue
        try:
            data = orjson.loads(message.data)
        except orjson.JSONDecodeError:
            continue
        name, is_call = kind
        if is_call:
            if isinstance(data, dict):
                builder.call(name, t_ns, data.get("request"), data.get("response"))
        else:
            builder.topic(name, t_ns, data)
    if last_ns >= 0:
        builder.mark_time(last_ns)  # messages no signal reads still extend the session
    return builder.finish()


def check_recording(
    path: str | os.PathLike[str], properties: PropertySet | Iterable[Property]
) -> CheckReport:
    signals = signals_from_recording(path)
    verdicts = evaluate(properties, signals)
    duration = round(max(0, signals.length - 1) * PERIOD_S, 6)
    return CheckReport(str(path), tuple(verdicts), duration)


def _inside(topic: str) -> str:
    """The topic inside the drone's namespace (`/drone1/vehicle/state` -> `vehicle/state`)."""
    parts = topic.split("/", 2)
    return parts[2] if len(parts) == 3 and parts[0] == "" else topic.lstrip("/")


def _num(value: float | None) -> str:
    if value is None:
        return "-"
    if value in (float("inf"), float("-inf")):
        return "inf" if value > 0 else "-inf"
    return f"{value + 0.0:.3g}"
