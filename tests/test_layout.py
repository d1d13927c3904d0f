"""`aeroexec layout --foxglove [--for REC]`: a layout in Foxglove's format (Foxglove
Studio's and Lichtblick's `LayoutData`) whose panels name what aeroexec recordings really
hold: each topic exists with the schema its panel reads, each message path resolves to
values of the right kind in a recorded session, the 3D panel's frames are the
recording's. With `--for`, for each kind of recording (run, replay in both modes, fly,
imports), every panel shows something and every log the recording has gets a panel."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.mission import APPENDIX_C, SessionConfig, simulate
from aeroexec.properties.monitor import PropertyMonitor
from aeroexec.properties.spec import load_properties
from aeroexec.viz.foxglove_layout import (
    foxglove_layout,
    generic_content,
    layout_text,
)

#: Panel types Foxglove Studio 1.x and Lichtblick register (their panels/index.ts).
PANEL_TYPES = {
    "3D",
    "Image",
    "Plot",
    "RawMessages",
    "RosOut",
    "StateTransitions",
    "Table",
    "Tab",
    "Indicator",
    "Gauge",
    "map",
    "Publish",
    "DiagnosticSummary",
    "DiagnosticStatusPanel",
    "SourceInfo",
    "TopicGraph",
    "Parameters",
    "Teleop",
}
_PATH = re.compile(r"^(/[\w/]+)(?:\{(\w+)=='([^']*)'\})?((?:\.\w+|\[\d+\])*)$")


@pytest.fixture(scope="module", params=["drone1", "drone2"])
def session(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Any:
    drone = request.param
    path = tmp_path_factory.mktemp("layout") / f"{drone}.mcap"
    # Monitored as `run --spec aeroexec:safety` is, so the properties channel is there too.
    monitor = PropertyMonitor(load_properties(["aeroexec:safety"]))
    simulate(SessionConfig(mission=APPENDIX_C, record=path, drone=drone), observers=[monitor])
    topics: dict[str, tuple[str, dict[str, Any], list[Any]]] = {}
    with open(path, "rb") as stream:
        for schema, channel, message in make_reader(stream).iter_messages():
            assert schema is not None
            entry = topics.setdefault(channel.topic, (schema.name, json.loads(schema.data), []))
            entry[2].append(json.loads(message.data))
    return drone, topics


def _leaves(node: Any) -> list[str]:
    if isinstance(node, str):
        return [node]
    assert set(node) == {"direction", "first", "second", "splitPercentage"}
    assert node["direction"] in ("row", "column")
    assert 0 < node["splitPercentage"] < 100
    return _leaves(node["first"]) + _leaves(node["second"])


def test_the_format_of_a_foxglove_layout() -> None:
    layout = json.loads(layout_text())
    assert {"configById", "layout", "globalVariables", "userNodes", "playbackConfig"} <= set(layout)
    assert layout["userNodes"] == {}  # no code in a layout
    assert layout["playbackConfig"]["speed"] == 1
    leaves = _leaves(layout["layout"])
    assert sorted(leaves) == sorted(layout["configById"])  # every panel placed, once
    types = [panel_id.split("!", 1)[0] for panel_id in leaves]
    assert set(types) <= PANEL_TYPES
    assert {"3D", "Plot", "StateTransitions", "RosOut"} <= set(types)
    assert layout_text() == layout_text()  # the same bytes every time


def _resolve(path: str, topics: dict[str, Any]) -> tuple[str, list[Any]]:
    """A Foxglove message path (`/topic.field[i]...`): its schema name and the values
    it gives, one per recorded message."""
    found = _PATH.match(path)
    assert found, path
    topic, key, wanted, rest = found.groups()
    assert topic in topics, topic
    name, schema, messages = topics[topic]
    if key is not None:  # a filter on the message: the others are skipped
        assert schema["properties"][key]["type"] == "string", (path, key)
        messages = [m for m in messages if m[key] == wanted]
    steps = re.findall(r"\.(\w+)|\[(\d+)\]", rest)
    node = schema
    for field, _ in steps:  # the path exists in the schema Foxglove parses
        if field:
            assert node["type"] == "object" and field in node["properties"], (path, field)
            node = node["properties"][field]
        else:
            assert node["type"] == "array", path
            node = node["items"]
    values = []
    for message in messages:
        value = message
        for field, index in steps:
            value = value[field] if field else value[int(index)]
        values.append(value)
    return name, values


def check_panels(
    config: dict[str, Any], topics: dict[str, Any], drone: str, *, every_capability: bool = True
) -> None:
    """Every panel of `config` shows something of the recording `topics` (each
    capability's timeline too, unless `every_capability` is false: the generic layout
    names the whole bundled catalog, which one session need not use)."""
    for panel_id, panel in config.items():
        kind = panel_id.split("!", 1)[0]
        if kind == "Plot":
            for series in panel["paths"]:
                _, values = _resolve(series["value"], topics)
                assert values and all(isinstance(v, (int, float)) for v in values), series
        elif kind == "StateTransitions":
            shown = 0
            for series in panel["paths"]:
                _, values = _resolve(series["value"], topics)
                shown += bool(values)
                assert values or (not every_capability and panel_id.endswith("!capabilities"))
                assert all(isinstance(v, str) for v in values) or all(
                    type(v) is int for v in values
                ), series
            assert shown, panel_id
        elif kind == "RosOut":
            name, _, messages = topics[panel["topicToRender"]]
            assert name in ("foxglove.Log", "rosgraph_msgs/Log") and messages
        elif kind == "RawMessages":
            assert panel["topicPath"] in topics
        elif kind == "3D":
            scenes = [t for t, v in panel["topics"].items() if v["visible"]]
            assert f"/{drone}/scene" in scenes
            for scene in scenes:
                assert scene not in topics or topics[scene][0] == "foxglove.SceneUpdate"
            transforms = [
                m
                for name, _, ms in topics.values()
                if name == "foxglove.FrameTransform"
                for m in ms
            ]
            assert transforms
            assert {m["parent_frame_id"] for m in transforms} == {panel["followTf"]}
            frames = {key.removeprefix("frame:") for key in panel["transforms"]}
            assert frames == {m["child_frame_id"] for m in transforms} == {f"{drone}/base_link"}
        else:
            raise AssertionError(f"a panel this test does not check: {panel_id}")


def test_every_panel_names_what_the_recording_holds(session: Any) -> None:
    drone, topics = session
    config = foxglove_layout(generic_content(drone))["configById"]
    check_panels(config, topics, drone, every_capability=False)
    # One timeline per capability, from the bundled catalog: those the session used
    # are among them, and each goes back to 0 when released.
    (capabilities,) = [p for i, p in config.items() if i == "StateTransitions!capabilities"]
    series = {s["label"]: s["value"] for s in capabilities["paths"]}
    used = {m["name"] for m in topics[f"/{drone}/capability_state"][2]}
    assert len(used) >= 3 and used <= set(series)
    for name in used:
        _, values = _resolve(series[name], topics)
        assert values[0] >= 1 and (values[-1] == 0 or name.startswith("SELF_LOCALIZATION"))


def _invoke(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, list(args))
    return result.exit_code, result.stdout, result.stderr


def test_cli_writes_the_file_or_standard_output(tmp_path: Path) -> None:
    target = tmp_path / "aeroexec.json"
    code, out, err = _invoke("layout", "--foxglove", "-o", str(target))
    assert code == 0 and out == "" and err == f"wrote {target}\n"
    assert target.read_text() == layout_text()
    code, out, _ = _invoke("layout", "--foxglove", "--drone", "drone2")
    assert code == 0 and out == layout_text(generic_content("drone2"))
    assert "/drone2/call_log" in out and "/drone1/" not in out
    assert list(tmp_path.iterdir()) == [target]  # no temporary file left


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ([], "aeroexec layout: error: choose the viewer the layout is for: --foxglove"),
        (
            ["--foxglove", "--drone", "a/b"],
            "aeroexec layout: error: --drone: a namespace is one name",
        ),
    ],
)
def test_cli_refuses_with_one_line(args: list[str], message: str) -> None:
    code, out, err = _invoke("layout", *args)
    assert code == 2 and out == ""
    assert err.startswith(message) and err.count("\n") == 1


def test_cli_unwritable_output(tmp_path: Path) -> None:
    code, _, err = _invoke("layout", "--foxglove", "-o", str(tmp_path))
    assert (
        code == 2
        and err == f"{tmp_path}: error: is a directory; give a file name ending in .json\n"
    )
    missing = tmp_path / "no" / "x.json"
    code, _, err = _invoke("layout", "--foxglove", "-o", str(missing))
    assert code == 2 and err.startswith(f"{missing}: error: cannot write:")
