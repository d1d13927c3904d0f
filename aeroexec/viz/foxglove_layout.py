"""A Foxglove (and Lichtblick) layout for aeroexec recordings, imported once by the user
("Import layout from file..."): `aeroexec layout --foxglove -o aeroexec.json`.

    +----------------------------------+------------------------------------+
    | Flight (3D: world frame, vehicle | Position (m) and battery (plot of  |
    |   body on <drone>/base_link,     |   vehicle/state)                   |
    |   markers, object, grid)         |------------------------------------|
    |                                  | Behavior events and properties     |
    |----------------------------------|   (state timeline: name and code   |
    |                                  |   of each event; property verdicts)|
    | Call log (Log panel:  | Log      |------------------------------------|
    |   call_log)           |          | Last behavior event (raw message)  |
    +----------------------------------+------------------------------------+

The file is Foxglove's layout format (`LayoutData` of Foxglove Studio and Lichtblick):
`configById` (panel id `<type>!<name>` -> the panel's config), `layout` (the mosaic tree
of panel ids: leaves are ids, branches `{direction, first, second, splitPercentage}`),
`globalVariables`, `userNodes`, `playbackConfig`. Panel configs name the channels of the
aeroexec profile (docs/recording.md), under the drone's namespace; the 3D panel shows the
`scene` topic (Foxglove hides scene topics until a layout or the user turns them on) in
the `world` frame. Nothing in it runs code (no user scripts).
"""

from __future__ import annotations

import json
from typing import Any

from aeroexec.recording.foxglove import WORLD_FRAME, vehicle_frame

#: Panel type (the part of a panel id before "!") of each panel, as Foxglove names them.
THREE_D = "3D"
PLOT = "Plot"
STATE_TRANSITIONS = "StateTransitions"
RAW_MESSAGES = "RawMessages"
LOG = "RosOut"  # Foxglove's Log panel
TITLE = "foxglovePanelTitle"
#: A fixed id for the grid layer, so the same command writes the same bytes.
GRID_ID = "6c3fd5f6-0c2a-4d4e-9a55-aeee0e0a0001"


def _path(value: str, label: str) -> dict[str, Any]:
    return {"value": value, "enabled": True, "timestampMethod": "receiveTime", "label": label}


def panels(drone: str = "drone1") -> dict[str, dict[str, Any]]:
    """Panel id -> config."""
    ns = f"/{drone}"
    state = f"{ns}/vehicle/state"
    event = f"{ns}/behavior_event"
    return {
        f"{THREE_D}!flight": {
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
            "topics": {f"{ns}/scene": {"visible": True}},
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
        },
        f"{PLOT}!position-battery": {
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
        },
        f"{STATE_TRANSITIONS}!behavior-events": {
            TITLE: "Behavior events and properties",
            "paths": [
                _path(f"{event}.name", "behavior"),
                _path(f"{event}.code", "event"),
                # run/fly --spec: each violation (and the final verdicts) as published.
                _path(f"{ns}/properties.property", "property"),
                _path(f"{ns}/properties.status", "verdict"),
            ],
            "isSynced": True,
            "showPoints": True,
        },
        f"{RAW_MESSAGES}!behavior-event": {
            TITLE: "Last behavior event",
            "topicPath": event,
            "diffEnabled": False,
            "diffMethod": "custom",
            "diffTopicPath": "",
            "showFullMessageForDiff": False,
            "expansion": "all",
        },
        f"{LOG}!call-log": {
            TITLE: "Call log",
            "topicToRender": f"{ns}/call_log",
            "searchTerms": [],
            "minLogLevel": 1,
        },
        f"{LOG}!log": {
            TITLE: "Log",
            "topicToRender": f"{ns}/log",
            "searchTerms": [],
            "minLogLevel": 1,
        },
    }


def _split(direction: str, first: Any, second: Any, percentage: int) -> dict[str, Any]:
    return {"direction": direction, "first": first, "second": second, "splitPercentage": percentage}


def mosaic() -> dict[str, Any]:
    """The arrangement: the flight and the logs on the left, plots and events right."""
    logs = _split("row", f"{LOG}!call-log", f"{LOG}!log", 55)
    left = _split("column", f"{THREE_D}!flight", logs, 62)
    events = _split(
        "column", f"{STATE_TRANSITIONS}!behavior-events", f"{RAW_MESSAGES}!behavior-event", 55
    )
    right = _split("column", f"{PLOT}!position-battery", events, 40)
    return _split("row", left, right, 58)


def foxglove_layout(drone: str = "drone1") -> dict[str, Any]:
    return {
        "configById": panels(drone),
        "globalVariables": {},
        "userNodes": {},
        "linkedGlobalVariables": [],
        "playbackConfig": {"speed": 1},
        "layout": mosaic(),
    }


def layout_text(drone: str = "drone1") -> str:
    """The layout file's text (indented, key order as written: the same every time)."""
    return json.dumps(foxglove_layout(drone), indent=2) + "\n"
