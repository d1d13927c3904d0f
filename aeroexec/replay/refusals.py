"""Which vehicle commands a recorded flight's autopilot refused, and when.

A command the vehicle refuses raises `VehicleCommandError` in the behavior that gave it,
and the behavior base class ends that behavior at once with PROCESS_FAILURE, its detail
`on_start failed: VehicleCommandError: <the refusal>` (or `on_run failed: ...`), plus
`; vehicle fault: <fault>` when the vehicle had one. The refusal's words are the
vehicle's own verdict, made from what the recording holds beside them: the COMMAND_ACK's
result and the autopilot's STATUSTEXT (`MAV_CMD_COMPONENT_ARM_DISARM refused: FAILED
(autopilot: Arm: ...)`, from `mavlink/rx`), no acknowledgement at all, or the link state
(`set_yaw: refused, link lost (no heartbeat for 1 s)`, `mavlink/link`). So the
`behavior_event`s are where closed-loop replay reads them: the time (the event's log
time), the behavior, the words without the fault suffix (the replayed behavior adds it
again from the replayed state).
"""

from __future__ import annotations

import json
from pathlib import Path

from aeroexec.replay.source import RecordingSource
from aeroexec.replay.vehicle import Refusal

EVENT_TOPIC = "behavior_event"
_MARK = "VehicleCommandError: "
_FAULT = "; vehicle fault: "


def refusal_words(detail: str) -> str | None:
    """The refusal in a PROCESS_FAILURE detail, or None if the vehicle refused nothing."""
    head, mark, words = detail.partition(_MARK)
    if not mark or not head.endswith(("on_start failed: ", "on_run failed: ")):
        return None
    cut = words.rfind(_FAULT)
    return words[:cut] if cut >= 0 else words


def recorded_refusals(path: str | Path) -> list[Refusal]:
    """The refusals of the recording at `path`, in time order."""
    found = []
    for message in RecordingSource(path).scan(lambda name: name == EVENT_TOPIC):
        try:
            event = json.loads(message.data)
        except ValueError:
            continue
        if not isinstance(event, dict) or event.get("code") != "PROCESS_FAILURE":
            continue
        words = refusal_words(str(event.get("detail", "")))
        if words is not None:
            found.append(Refusal(message.log_time_ns, str(event.get("name", "")), words))
    found.sort(key=lambda r: r.time_ns)
    return found
