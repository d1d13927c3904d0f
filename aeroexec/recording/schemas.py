"""The JSON Schemas of the aeroexec MCAP profile, one per kind of channel.

Every channel of an aeroexec recording carries a schema (encoding `jsonschema`) so that
Foxglove, Lichtblick, the `mcap` CLI and any JSON Schema validator can check its
messages. The executive's own payloads are described by their required fields and stay
open (`additionalProperties` allowed): a later core version may add a field without
making older readers reject the file.

**The viewers' dialect.** Foxglove Studio and Lichtblick turn a channel's schema into
message datatypes with their own `parseJsonSchema`, which accepts a narrow part of JSON
Schema and hides a channel whose schema it rejects. So every schema here keeps to it: one
`type` string per field (never `["integer", "null"]`: a value that can be absent is a
key left out, not a null), `enum` only beside a `type`, `properties` on every object
(`{}` for a free-form one), `items` on every array, `oneOf` only of numeric `const`s.
`tests/test_foxglove_compat.py` runs both viewers' parsers on every schema.

Foxglove's well-known schemas: `foxglove.Log` follows Foxglove's field layout;
`foxglove.FrameTransform` and `foxglove.SceneUpdate` are Foxglove's own files, shipped
unchanged in `aeroexec/data/foxglove/` and written without their descriptions, so the
Log and 3D panels recognize the channels.

Each schema's bytes are produced once, with sorted keys and no whitespace, so the same
code always writes the same schema record.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

#: The MCAP header profile of an aeroexec recording.
PROFILE = "aeroexec"
SCHEMA_ENCODING = "jsonschema"
MESSAGE_ENCODING = "json"
#: The metadata record saying which code implemented each behavior
#: (`aeroexec.plugins.manifest` writes it; readers need no plugin code to read it).
CODE_METADATA_NAME = "behaviors"

SERVICE_CALL = "aeroexec.ServiceCall"
BEHAVIOR_EVENT = "aeroexec.BehaviorEvent"
ACTIVE_BEHAVIORS = "aeroexec.ActiveBehaviors"
ACTIVE_CAPABILITIES = "aeroexec.ActiveCapabilities"
CAPABILITY_STATE = "aeroexec.CapabilityState"
PROCESS_STATE = "aeroexec.ProcessState"
BELIEF_CHANGE = "aeroexec.BeliefChange"
MISSION_COMMAND = "aeroexec.MissionCommand"
VEHICLE_STATE = "aeroexec.VehicleState"
GENERIC_TOPIC = "aeroexec.Topic"
PROPERTY_VERDICT = "aeroexec.PropertyVerdict"
FOXGLOVE_LOG = "foxglove.Log"
FOXGLOVE_FRAME_TRANSFORM = "foxglove.FrameTransform"
FOXGLOVE_SCENE_UPDATE = "foxglove.SceneUpdate"

#: Foxglove's own schema files, shipped unchanged (see aeroexec/data/foxglove/SOURCES.md).
FOXGLOVE_SCHEMA_DIR = Path(__file__).resolve().parent.parent / "data" / "foxglove"
FOXGLOVE_FILES: dict[str, str] = {
    FOXGLOVE_FRAME_TRANSFORM: "FrameTransform.json",
    FOXGLOVE_SCENE_UPDATE: "SceneUpdate.json",
}

_TIME: dict[str, Any] = {
    "type": "object",
    "title": "time",
    "properties": {
        "sec": {"type": "integer", "minimum": 0},
        "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999},
    },
    "required": ["sec", "nsec"],
}

_VECTOR3: dict[str, Any] = {
    "type": "array",
    "items": {"type": "number"},
    "minItems": 3,
    "maxItems": 3,
}

#: An object whose keys are the caller's (behavior arguments, a service's request).
_FREE_OBJECT: dict[str, Any] = {"type": "object", "properties": {}}

_EVENT_CODES = [
    "GOAL_ACHIEVED",
    "TIME_OUT",
    "WRONG_PROGRESS",
    "ASSUMPTION_CONFLICT",
    "INTERRUPTED",
    "PROCESS_FAILURE",
]


def _object(
    title: str, description: str, properties: dict[str, Any], required: list[str]
) -> dict[str, Any]:
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": title,
        "description": description,
        "type": "object",
        "properties": properties,
        "required": required,
    }


SCHEMAS: dict[str, dict[str, Any]] = {
    SERVICE_CALL: _object(
        SERVICE_CALL,
        "A completed service call of the executive. seq is the call's start order; "
        "parent_seq the call it happened inside (absent for a call made at the top).",
        {
            "seq": {"type": "integer", "minimum": 0},
            "parent_seq": {"type": "integer", "minimum": 0},
            "caller": {"type": "string"},
            "service": {"type": "string"},
            "request": _FREE_OBJECT,
            "response": {
                "type": "object",
                "properties": {"ok": {"type": "boolean"}, "error": {"type": "string"}},
                "required": ["ok", "error"],
            },
            # Imported from a bag: a call the importer inferred (bags hold no calls).
            "reconstructed": {"type": "boolean"},
        },
        ["seq", "caller", "service", "request", "response"],
    ),
    BEHAVIOR_EVENT: _object(
        BEHAVIOR_EVENT,
        "A behavior activation's one end event.",
        {
            "name": {"type": "string"},
            "uid": {"type": "integer"},
            "code": {"type": "string", "enum": _EVENT_CODES},
            "detail": {"type": "string"},
            # Imported from a bag: the event was inferred, or the uid the bag gave it.
            "reconstructed": {"type": "boolean"},
            "bag_uid": {"type": "number"},
        },
        ["name", "uid", "code"],
    ),
    ACTIVE_BEHAVIORS: _object(
        ACTIVE_BEHAVIORS,
        "The behaviors active now, in catalog order.",
        {"behaviors": {"type": "array", "items": {"type": "string"}}},
        ["behaviors"],
    ),
    CAPABILITY_STATE: _object(
        CAPABILITY_STATE,
        "A capability whose reference count changed, and the count now (0: released).",
        {"name": {"type": "string"}, "references": {"type": "integer", "minimum": 0}},
        ["name", "references"],
    ),
    ACTIVE_CAPABILITIES: _object(
        ACTIVE_CAPABILITIES,
        "The referenced capabilities with their reference counts, in catalog order.",
        {
            "capabilities": {
                "type": "array",
                "items": {
                    "type": "object",
                    "properties": {
                        "name": {"type": "string"},
                        "references": {"type": "integer", "minimum": 1},
                    },
                    "required": ["name", "references"],
                },
            },
            # Imported from a bag, whose list has no reference counts: false.
            "counts_known": {"type": "boolean"},
        },
        ["capabilities"],
    ),
    PROCESS_STATE: _object(
        PROCESS_STATE,
        "A process started or stopped by the resource manager.",
        {"process": {"type": "string"}, "state": {"type": "string"}},
        ["process", "state"],
    ),
    BELIEF_CHANGE: _object(
        BELIEF_CHANGE,
        "A change of the belief store: op is add, remove or replace (belief replaces "
        "replaced, a belief with the same key: one message for a remove and an add).",
        {
            "op": {"type": "string"},
            "belief": {"type": "string"},
            "replaced": {"type": "string"},
        },
        ["op", "belief"],
    ),
    MISSION_COMMAND: _object(
        MISSION_COMMAND,
        "An external input: what the mission asked of the executive, and when. The "
        "fields besides command are those the command takes.",
        {
            "command": {"type": "string"},
            "behavior": {"type": "string"},
            "arguments": _FREE_OBJECT,
            "query": {"type": "string"},
            "belief": {"type": "string"},
            # The mission script's line that made the call (absent when not known).
            "line": {"type": "integer", "minimum": 1},
            # Imported from a bag: the command was inferred from the active list, and how.
            "reconstructed": {"type": "boolean"},
            "evidence": {"type": "string"},
        },
        ["command"],
    ),
    VEHICLE_STATE: _object(
        VEHICLE_STATE,
        "The vehicle's state estimate (local ENU metres, yaw in radians).",
        {
            "position": _VECTOR3,
            "velocity": _VECTOR3,
            "yaw": {"type": "number"},
            "battery": {"type": "number"},
            "flying": {"type": "boolean"},
            "armed": {"type": "boolean"},
            "fault": {"type": "string"},
            # Imported from a bag: the fields the bag did not give, filled with defaults.
            "defaulted": {"type": "array", "items": {"type": "string"}},
        },
        ["position", "velocity", "yaw", "battery", "flying"],
    ),
    GENERIC_TOPIC: _object(
        GENERIC_TOPIC, "A topic of the executive without a dedicated schema.", {}, []
    ),
    PROPERTY_VERDICT: _object(
        PROPERTY_VERDICT,
        "A property of run/fly --spec (docs/properties.md): violated (when seen during the "
        "session, or at its end) or its final verdict; t_s is when the first violating "
        "interval starts.",
        {
            "property": {"type": "string"},
            "status": {"type": "string"},
            "severity": {"type": "string"},
            "t_s": {"type": "number"},
            "end_s": {"type": "number"},
            "robustness": {"type": "number"},
            "action": {"type": "string"},
            "defined_at": {"type": "string"},
            "message": {"type": "string"},
        },
        ["property", "status"],
    ),
    FOXGLOVE_LOG: {
        "title": FOXGLOVE_LOG,
        "description": "A log message",
        "type": "object",
        "properties": {
            "timestamp": _TIME,
            "level": {
                "title": "foxglove.LogLevel",
                "oneOf": [
                    {"title": "UNKNOWN", "const": 0},
                    {"title": "DEBUG", "const": 1},
                    {"title": "INFO", "const": 2},
                    {"title": "WARNING", "const": 3},
                    {"title": "ERROR", "const": 4},
                    {"title": "FATAL", "const": 5},
                ],
            },
            "message": {"type": "string"},
            "name": {"type": "string"},
            "file": {"type": "string"},
            "line": {"type": "integer", "minimum": 0},
        },
        "required": ["timestamp", "level", "message", "name", "file", "line"],
    },
}

#: The topic (in the drone's namespace) property verdicts are published on (`--spec`).
PROPERTIES_TOPIC = "properties"

#: Topic (relative to `/<drone>/`) -> schema name. Services all use SERVICE_CALL; a topic
#: missing here gets GENERIC_TOPIC.
TOPIC_SCHEMAS: dict[str, str] = {
    "behavior_event": BEHAVIOR_EVENT,
    "list_of_active_behaviors": ACTIVE_BEHAVIORS,
    "list_of_active_capabilities": ACTIVE_CAPABILITIES,
    "capability_state": CAPABILITY_STATE,
    "process_state": PROCESS_STATE,
    "beliefs": BELIEF_CHANGE,
    "mission/command": MISSION_COMMAND,
    "vehicle/state": VEHICLE_STATE,
    "vehicle/transform": FOXGLOVE_FRAME_TRANSFORM,
    "scene": FOXGLOVE_SCENE_UPDATE,
    "scene/static": FOXGLOVE_SCENE_UPDATE,
    "log": FOXGLOVE_LOG,
    "call_log": FOXGLOVE_LOG,
    PROPERTIES_TOPIC: PROPERTY_VERDICT,
}

#: foxglove.LogLevel values by name (Python's logging names included).
LOG_LEVELS: dict[str, int] = {
    "DEBUG": 1,
    "INFO": 2,
    "WARNING": 3,
    "WARN": 3,
    "ERROR": 4,
    "FATAL": 5,
    "CRITICAL": 5,
}


@dataclass(frozen=True, slots=True)
class SchemaDef:
    name: str
    data: bytes


def schema_document(name: str) -> dict[str, Any]:
    """The JSON Schema named `name` (KeyError for a name outside the profile)."""
    if name in FOXGLOVE_FILES:
        return _foxglove_document(name)
    return SCHEMAS[name]


@cache
def _foxglove_document(name: str) -> dict[str, Any]:
    """Foxglove's schema file without its prose: every schema in every recording carries
    it (twice: in a chunk and in the summary), and SceneUpdate's descriptions are half of
    its 21 kB. The definitions (types, fields, required, titles) are Foxglove's."""
    document: dict[str, Any] = json.loads(
        (FOXGLOVE_SCHEMA_DIR / FOXGLOVE_FILES[name]).read_text(encoding="utf-8")
    )
    return _without_prose(document)


_PROSE = frozenset({"description", "$comment"})


def _without_prose(schema: dict[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in schema.items():
        if key in _PROSE:
            continue
        if key == "properties":  # field names -> schemas (a field may be named "description")
            out[key] = {field: _without_prose(sub) for field, sub in value.items()}
        elif key == "items" and isinstance(value, dict):
            out[key] = _without_prose(value)
        elif key == "oneOf":
            out[key] = [_without_prose(sub) for sub in value]
        else:
            out[key] = value
    return out


@cache
def schema_for(name: str) -> SchemaDef:
    """The schema record content for `name` (compact, key-sorted JSON)."""
    text = json.dumps(schema_document(name), sort_keys=True, separators=(",", ":"))
    return SchemaDef(name, text.encode())


def profile_schema_names() -> list[str]:
    """Every schema the profile writes."""
    return [*SCHEMAS, *FOXGLOVE_FILES]


def schema_name_for_topic(topic: str) -> str:
    return TOPIC_SCHEMAS.get(topic, GENERIC_TOPIC)
