"""The text and level of each text-log row the converter writes.

Levels are Rerun's `TextLogLevel` names, so the viewer's level filter works: behavior
events by outcome (a goal achieved or an interruption is routine, a timeout or a wrong
progress is a warning, a process failure is an error), rejected activations as warnings,
other failed calls and vehicle faults as errors.
"""

from __future__ import annotations

import json
from typing import Any

from aeroexec.recording.reader import RecordedCall

TRACE = "TRACE"
DEBUG = "DEBUG"
INFO = "INFO"
WARN = "WARN"
ERROR = "ERROR"
CRITICAL = "CRITICAL"

#: Level of a behavior_event by its code (unknown codes: WARN).
EVENT_LEVELS = {
    "GOAL_ACHIEVED": INFO,
    "INTERRUPTED": INFO,
    "TIME_OUT": WARN,
    "WRONG_PROGRESS": WARN,
    "ASSUMPTION_CONFLICT": WARN,
    "PROCESS_FAILURE": ERROR,
}

#: foxglove.Log levels (1 DEBUG .. 5 FATAL; 0 UNKNOWN) as Rerun levels.
FOXGLOVE_LEVELS = {0: INFO, 1: DEBUG, 2: INFO, 3: WARN, 4: ERROR, 5: CRITICAL}

#: Longest request/response text shown in one call-tree row.
MAX_DETAIL = 160


def compact(value: Any, limit: int = MAX_DETAIL) -> str:
    """Short one-line JSON for a request or arguments (cut with an ellipsis)."""
    try:
        text = json.dumps(value, separators=(", ", ": "), sort_keys=False, default=str)
    except (TypeError, ValueError):
        text = repr(value)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def arguments_text(arguments: Any) -> str:
    """`coordinates=[3, 5.5, 1.3] speed=1` as the run command prints them."""
    if not isinstance(arguments, dict) or not arguments:
        return ""
    return " ".join(f"{key}={compact(value, 60)}" for key, value in arguments.items())


def event_row(data: Any) -> tuple[str, str]:
    if not isinstance(data, dict):
        return f"behavior_event: {compact(data)}", WARN
    name = str(data.get("name", "?"))
    uid = data.get("uid")
    code = str(data.get("code", "?"))
    detail = str(data.get("detail", "") or "")
    who = f"{name} #{uid}" if uid is not None else name
    text = f"{who} {code}" + (f": {detail}" if detail else "")
    return text, EVENT_LEVELS.get(code, WARN)


def rejection_row(call: RecordedCall) -> tuple[str, str]:
    """A refused root call: activations are warnings (the mission was told no)."""
    if call.service.endswith("activate_behavior"):
        behavior = str(call.request.get("behavior", "?"))
        args = arguments_text(call.request.get("arguments"))
        what = f"{behavior} {args}".rstrip()
        return f"REJECTED {what}: {call.error or 'refused'}", WARN
    return f"{call.service} failed: {call.error or 'refused'}", ERROR


def call_row(call: RecordedCall, depth: int) -> tuple[str, str]:
    indent = "  " * depth
    request = compact(call.request) if call.request else ""
    head = f"{indent}[{call.seq}] {call.caller} -> {call.service}"
    if request:
        head += f" {request}"
    extra = {k: v for k, v in call.response.items() if k not in ("ok", "error")}
    answer = f" {compact(extra, 80)}" if extra else ""
    if call.ok:
        return f"{head}: ok{answer}", INFO if depth == 0 else DEBUG
    if call.error:
        return f"{head}: FAILED: {call.error}", WARN
    return f"{head}: no{answer}", WARN


def mission_row(data: Any) -> tuple[str, str]:
    if not isinstance(data, dict):
        return compact(data), INFO
    command = str(data.get("command", "?"))
    rest = {k: v for k, v in data.items() if k != "command"}
    if "behavior" in rest:
        behavior = rest.pop("behavior")
        args = arguments_text(rest.pop("arguments", {}))
        text = f"{command} {behavior} {args}".rstrip()
    else:
        text = command
    if rest:
        text += " " + " ".join(f"{k}={compact(v, 80)}" for k, v in rest.items())
    return text, INFO


def belief_row(data: Any) -> tuple[str, str]:
    if not isinstance(data, dict):
        return compact(data), DEBUG
    op = str(data.get("op", "?"))
    belief = str(data.get("belief", ""))
    if op == "replace":
        return f"+ {belief} (- {data.get('replaced', '')})", DEBUG
    sign = {"add": "+", "remove": "-"}.get(op, op)
    return f"{sign} {belief}", DEBUG


def log_row(data: Any) -> tuple[str, str]:
    if not isinstance(data, dict):
        return compact(data), INFO
    level = data.get("level")
    message = str(data.get("message", ""))
    name = str(data.get("name", "") or "")
    text = message if not name or message.startswith(name) else f"{name}: {message}"
    return text, FOXGLOVE_LEVELS.get(level, INFO) if isinstance(level, int) else INFO
