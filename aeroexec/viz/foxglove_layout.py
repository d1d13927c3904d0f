"""A Foxglove (and Lichtblick) layout for aeroexec recordings, imported once by the user
from the viewer's layout browser, "Import from file..." (Lichtblick: the Layouts tab of
the left sidebar; Foxglove: the top bar's layout menu): `aeroexec layout --foxglove`.

    +----------------------------------+------------------------------------+
    | Flight (3D: world frame, vehicle | Position (m) and battery (plot of  |
    |   body on <drone>/base_link,     |   vehicle/state)                   |
    |   markers, object, grid)         |------------------------------------|
    |                                  | Behavior events and properties     |
    |                                  |------------------------------------|
    |----------------------------------| Capabilities (one state timeline  |
    | Call log (Log panel:  | Log      |   per capability: its references)  |
    |   call_log)           |          |------------------------------------|
    |                       |          | Last behavior event (raw message)  |
    +----------------------------------+------------------------------------+

`LayoutContent` says what goes in: the generic layout (`generic_content`) is for the
sessions `aeroexec run` records (the capabilities of the bundled catalog, the call log
and the session's log); `content_for(recording)` (`layout --for REC`) takes what one
recording holds, so each kind of recording gets panels that show something: a flight or
an open-loop replay has no session log, an import has its bag's `rosout` instead (raw
`rosgraph_msgs/Log`, which the Log panel reads), a bag without behavior topics has no
behavior events and no call log. A panel whose topics the recording lacks is left out.

The file is Foxglove's layout format (`LayoutData` of Foxglove Studio and Lichtblick):
`configById` (panel id `<type>!<name>` -> the panel's config), `layout` (the mosaic tree
of panel ids: leaves are ids, branches `{direction, first, second, splitPercentage}`),
`globalVariables`, `userNodes`, `playbackConfig`. Panel configs name the channels of the
aeroexec profile (docs/recording.md), under the drone's namespace; the 3D panel shows the
scene topics (Foxglove hides scene topics until a layout or the user turns them on) in
the `world` frame. Nothing in it runs code (no user scripts).
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from typing import Any

import orjson

from aeroexec.catalog.loader import load_catalog
from aeroexec.catalog.paths import DEFAULT_CATALOG
from aeroexec.errors import Mark, RecordingError
from aeroexec.recording.foxglove import (
    CALL_LOG_TOPIC,
    CAPABILITY_TOPIC,
    SCENE_TOPIC,
    STATIC_SCENE_TOPIC,
    WORLD_FRAME,
    vehicle_frame,
)
from aeroexec.recording.reader import Recording
from aeroexec.recording.schemas import PROPERTIES_TOPIC

#: Panel type (the part of a panel id before "!") of each panel, as Foxglove names them.
THREE_D = "3D"
PLOT = "Plot"
STATE_TRANSITIONS = "StateTransitions"
RAW_MESSAGES = "RawMessages"
LOG = "RosOut"  # Foxglove's Log panel
TITLE = "foxglovePanelTitle"
#: A fixed id for the grid layer, so the same command writes the same bytes.
GRID_ID = "6c3fd5f6-0c2a-4d4e-9a55-aeee0e0a0001"
#: The schema of a bag's log messages, which the Log panel reads as it reads foxglove.Log.
ROS_LOG_SCHEMA = "rosgraph_msgs/Log"
#: A name a message path filter can quote as it is.
_FILTERABLE = re.compile(r"^[\w.\-/ ]+$")


@dataclass(frozen=True, slots=True)
class LayoutContent:
    """What a layout shows: the drone's namespace and the panels' sources."""

    drone: str = "drone1"
    #: The 3D panel's scene, and the vehicle's frame (vehicle/transform).
    flight: bool = True
    #: The plot of vehicle/state.
    vehicle: bool = True
    #: The behavior events' state timeline and the last event.
    behaviors: bool = True
    #: The property verdicts of `run/fly --spec` on the behavior events' timeline.
    properties: bool = True
    #: One state timeline per capability (its reference count, on capability_state).
    capabilities: tuple[str, ...] = ()
    #: Log panels: (topic, title), left to right.
    logs: tuple[tuple[str, str], ...] = ()


def generic_content(drone: str = "drone1") -> LayoutContent:
    """The layout for `aeroexec run`'s sessions: the bundled catalog's capabilities, the
    call log and the session's log."""
    ns = f"/{drone}"
    return LayoutContent(
        drone=drone,
        capabilities=tuple(load_catalog(DEFAULT_CATALOG).capabilities),
        logs=((f"{ns}/{CALL_LOG_TOPIC}", "Call log"), (f"{ns}/log", "Log")),
    )


def content_for(recording: Recording) -> LayoutContent:
    """The layout for what `recording` holds (two passes: a survey, then the
    capability_state messages for the capabilities' names, in order of appearance)."""
    survey = recording.survey()
    counts = survey.topic_counts()
    drone = (survey.metadata.get("aeroexec") or {}).get("drone") or "drone1"
    ns = f"/{drone}"

    def has(topic: str) -> bool:
        return counts.get(f"{ns}/{topic}", 0) > 0

    logs = [
        (f"{ns}/{topic}", title)
        for topic, title in ((CALL_LOG_TOPIC, "Call log"), ("log", "Log"))
        if has(topic)
    ]
    ros_logs = [  # a bag's own log: its rosout (rosout_agg repeats it), or the first
        channel.topic
        for cid, channel in survey.channels.items()
        if channel.schema_name == ROS_LOG_SCHEMA and survey.counts.get(cid, 0)
    ]
    if ros_logs:
        rosout = [t for t in ros_logs if t.endswith("/rosout")] or ros_logs
        logs.append((rosout[0], f"ROS log ({rosout[0]})"))
    names: dict[str, None] = {}
    if has(CAPABILITY_TOPIC):
        topic = f"{ns}/{CAPABILITY_TOPIC}"
        for message in recording.messages():
            if message.channel.topic == topic:
                name = orjson.loads(message.data).get("name")
                if isinstance(name, str):
                    names.setdefault(name)
    content = LayoutContent(
        drone=drone,
        flight=has(SCENE_TOPIC),
        vehicle=has("vehicle/state"),
        behaviors=has("behavior_event"),
        properties=has(PROPERTIES_TOPIC),
        capabilities=tuple(names),
        logs=tuple(logs),
    )
    if not panels(content):
        raise RecordingError(
            f"none of the channels a layout shows (under /{drone}/)", Mark(recording.name)
        )
    return content


def _path(value: str, label: str) -> dict[str, Any]:
    return {"value": value, "enabled": True, "timestampMethod": "receiveTime", "label": label}


def _three_d(drone: str) -> dict[str, Any]:
    ns = f"/{drone}"
    return {
        TITLE: "Flight",
        "followTf": WORLD_FRAME,
        "followMode": "follow-pose",
        "cameraState": {
            "distance": 18,
            "perspective": True,
            "phi": 55,
            "thetaOffset": 135,
            "target": [0, 0, 0],
            "targetOffset": [2, 3, 0],
            "targetOrientation": [0, 0, 0, 1],
            "fovy": 45,
            "near": 0.5,
            "far": 5000,
        },
        "scene": {"transforms": {"showLabel": True, "axisScale": 0.6}},
        "transforms": {f"frame:{vehicle_frame(drone)}": {"visible": True}},
        "topics": {
            f"{ns}/{STATIC_SCENE_TOPIC}": {"visible": True},
            f"{ns}/{SCENE_TOPIC}": {"visible": True},
        },
        "layers": {
            GRID_ID: {
                "visible": True,
                "frameLocked": True,
                "label": "Grid",
                "instanceId": GRID_ID,
                "layerId": "foxglove.Grid",
                "frameId": WORLD_FRAME,
                "size": 20,
                "divisions": 20,
                "lineWidth": 1,
                "color": "#248eff",
                "position": [0, 0, 0],
                "rotation": [0, 0, 0],
                "order": 1,
            }
        },
        "imageMode": {},
    }


def _log_id(topic: str) -> str:
    return f"{LOG}!" + (topic.strip("/").replace("/", "-") or "log")


def panels(content: LayoutContent) -> dict[str, dict[str, Any]]:
    """Panel id -> config, for what `content` holds."""
    ns = f"/{content.drone}"
    state = f"{ns}/vehicle/state"
    event = f"{ns}/behavior_event"
    out: dict[str, dict[str, Any]] = {}
    if content.flight:
        out[f"{THREE_D}!flight"] = _three_d(content.drone)
    if content.vehicle:
        out[f"{PLOT}!position-battery"] = {
            TITLE: "Position (m) and battery (0..1)",
            "paths": [
                _path(f"{state}.position[0]", "x (east)"),
                _path(f"{state}.position[1]", "y (north)"),
                _path(f"{state}.position[2]", "z (up)"),
                _path(f"{state}.battery", "battery"),
            ],
            "showXAxisLabels": True,
            "showYAxisLabels": True,
            "showLegend": True,
            "legendDisplay": "floating",
            "showPlotValuesInLegend": True,
            "isSynced": True,
            "xAxisVal": "timestamp",
            "sidebarDimension": 240,
        }
    if content.behaviors:
        paths = [_path(f"{event}.name", "behavior"), _path(f"{event}.code", "event")]
        if content.properties:  # run/fly --spec: each violation and the final verdicts
            verdicts = f"{ns}/{PROPERTIES_TOPIC}"
            paths += [
                _path(f"{verdicts}.property", "property"),
                _path(f"{verdicts}.status", "verdict"),
            ]
        out[f"{STATE_TRANSITIONS}!behavior-events"] = {
            TITLE: "Behavior events and properties" if content.properties else "Behavior events",
            "paths": paths,
            "isSynced": True,
            "showPoints": True,
        }
    capabilities = [c for c in content.capabilities if _FILTERABLE.match(c)]
    if capabilities:
        topic = f"{ns}/{CAPABILITY_TOPIC}"
        out[f"{STATE_TRANSITIONS}!capabilities"] = {
            TITLE: "Capabilities (references; 0 = released)",
            "paths": [_path(f"{topic}{{name=='{c}'}}.references", c) for c in capabilities],
            "isSynced": True,
            "showPoints": True,
        }
    if content.behaviors:
        out[f"{RAW_MESSAGES}!behavior-event"] = {
            TITLE: "Last behavior event",
            "topicPath": event,
            "diffEnabled": False,
            "diffMethod": "custom",
            "diffTopicPath": "",
            "showFullMessageForDiff": False,
            "expansion": "all",
        }
    for topic, title in content.logs:
        out[_log_id(topic)] = {
            TITLE: title,
            "topicToRender": topic,
            "searchTerms": [],
            "minLogLevel": 1,
        }
    return out


def _split(direction: str, first: Any, second: Any, percentage: int) -> dict[str, Any]:
    return {"direction": direction, "first": first, "second": second, "splitPercentage": percentage}


def _stack(direction: str, ids: list[str]) -> Any:
    """`ids` side by side (row) or one above the other (column), in equal shares."""
    if len(ids) == 1:
        return ids[0]
    return _split(direction, ids[0], _stack(direction, ids[1:]), round(100 / len(ids)))


def mosaic(ids: list[str]) -> Any:
    """The arrangement: the flight over the logs on the left, plots and timelines right."""
    logs = [i for i in ids if i.startswith(f"{LOG}!")]
    flight = [i for i in ids if i.startswith(f"{THREE_D}!")]
    right = [i for i in ids if i not in logs and i not in flight]
    columns = []
    left = [*flight, *([_stack("row", logs)] if logs else [])]
    if left:
        columns.append(_split("column", *left, 62) if len(left) == 2 else left[0])
    if right:
        columns.append(_stack("column", right))
    if not columns:
        raise ValueError("a layout needs a panel")
    return _split("row", columns[0], columns[1], 58) if len(columns) == 2 else columns[0]


def foxglove_layout(content: LayoutContent | None = None) -> dict[str, Any]:
    config = panels(content if content is not None else generic_content())
    return {
        "configById": config,
        "globalVariables": {},
        "userNodes": {},
        "linkedGlobalVariables": [],
        "playbackConfig": {"speed": 1},
        "layout": mosaic(list(config)),
    }


def layout_text(content: LayoutContent | None = None) -> str:
    """The layout file's text (indented, key order as written: the same every time)."""
    return json.dumps(foxglove_layout(content), indent=2) + "\n"
