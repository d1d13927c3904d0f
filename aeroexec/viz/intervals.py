"""Behavior intervals and capability reference counts as step series, streaming.

`BehaviorIntervals` turns accepted `activate_behavior` calls and `behavior_event`
messages into 1/0 transitions per behavior, matched by activation uid. It keeps only
each behavior's current activation (plus the rare uid whose end event was read before its
activation, and activations replaced before their end event arrived), so memory does not
grow with the recording.

In a recording, a completed call is written when the call returns, so its end event can
precede it in the file: a behavior whose start fails ends (PROCESS_FAILURE) inside the
`activate_behavior` call that started it. Such an early end is remembered and applied
right after the activation. When a new activation replaces the current one before the
latter's end event has been read, that later event no longer changes the series.

`CapabilityCounts` turns `list_of_active_capabilities` messages (the full list each
time) into per-capability count changes; a capability missing from the list is at 0.

Both report, at `finish`, the last value of every series so the step lines can be drawn
to the end of the session.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True, slots=True)
class Transition:
    """Behavior `name` becomes active (`label` says which activation) or inactive."""

    name: str
    t_ns: int
    active: bool
    uid: int | None = None
    label: str = ""


@dataclass(slots=True)
class _Behavior:
    uid: int | None = None  # the active activation, None when inactive
    superseded: set[int] = field(default_factory=set)  # replaced, end event not read yet


class BehaviorIntervals:
    def __init__(self) -> None:
        self._behaviors: dict[str, _Behavior] = {}
        self._early_ends: dict[int, int] = {}  # uid -> end time, activation not read yet

    @property
    def names(self) -> list[str]:
        return list(self._behaviors)

    def active(self, name: str) -> int | None:
        """The uid of `name`'s current activation (None when inactive or unknown)."""
        behavior = self._behaviors.get(name)
        return behavior.uid if behavior else None

    def activated(self, name: str, uid: int, t_ns: int, label: str = "") -> list[Transition]:
        behavior = self._behaviors.setdefault(name, _Behavior())
        out = [Transition(name, t_ns, True, uid, label)]
        ended = self._early_ends.pop(uid, None)
        if ended is not None:
            out.append(Transition(name, max(ended, t_ns), False, uid))
            return out
        if behavior.uid is not None and behavior.uid != uid:
            behavior.superseded.add(behavior.uid)
        behavior.uid = uid
        return out

    def ended(self, name: str, uid: int | None, t_ns: int) -> list[Transition]:
        behavior = self._behaviors.setdefault(name, _Behavior())
        if uid is not None and uid in behavior.superseded:
            behavior.superseded.discard(uid)
            return []
        if behavior.uid is not None and (uid is None or uid == behavior.uid):
            ended_uid = behavior.uid
            behavior.uid = None
            return [Transition(name, t_ns, False, ended_uid)]
        if uid is not None:
            self._early_ends[uid] = t_ns
        return []

    def finish(self, t_ns: int) -> list[Transition]:
        """Each behavior's state at `t_ns` (the end of the session)."""
        return [
            Transition(name, t_ns, behavior.uid is not None, behavior.uid)
            for name, behavior in self._behaviors.items()
        ]


class CapabilityCounts:
    def __init__(self) -> None:
        self._counts: dict[str, int] = {}

    @property
    def counts(self) -> dict[str, int]:
        return dict(self._counts)

    def update(self, capabilities: Any) -> list[tuple[str, int]]:
        """The (name, count) pairs that changed; `capabilities` is the message's list of
        `{name, references}` (entries that are not of that shape are skipped)."""
        now: dict[str, int] = {}
        if isinstance(capabilities, list):
            for item in capabilities:
                if not isinstance(item, dict) or not isinstance(item.get("name"), str):
                    continue
                references = item.get("references", 1)
                now[item["name"]] = references if isinstance(references, int) else 1
        changes: list[tuple[str, int]] = []
        for name, count in now.items():
            if self._counts.get(name) != count:
                changes.append((name, count))
        for name, count in self._counts.items():
            if name not in now and count != 0:
                changes.append((name, 0))
        for name, count in changes:
            self._counts[name] = count
        return changes
