"""`aeroexec layout --foxglove --for REC`: a layout for what each kind of recording holds
(issue 28). The generic layout's Log panel (`/drone1/log`) stays empty for a flight, an
open-loop replay or an import; the layout for a recording shows the logs it has (an
import's bag `rosout` among them), leaves out panels with nothing to show, and has one
capability timeline per capability the recording used."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader
from test_bags_support import AEROSTACK_BAG, TURTLE_LZ4, short_mission
from test_layout import check_panels
from test_mavlink_flight import Proc, free_udp_port, start_mavsim, stop_mavsim, write_mission
from typer.testing import CliRunner

from aeroexec.bags import import_bag
from aeroexec.cli import app
from aeroexec.mission import APPENDIX_C, SessionConfig, simulate
from aeroexec.mission.live import FlightConfig, fly
from aeroexec.replay import Mode, ReplayOptions, replay_recording
from aeroexec.viz.foxglove_layout import content_for, foxglove_layout, layout_text
from aeroexec.viz.view import open_session

ROS2_MCAP = Path(__file__).parent / "fixtures" / "recording" / "mcap_ros2_talker_zstd.mcap"


@pytest.fixture(scope="module")
def kinds(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Path]]:
    folder = tmp_path_factory.mktemp("kinds")
    out = {name: folder / f"{name}.mcap" for name in ("run", "closed", "open", "fly")}
    simulate(SessionConfig(mission=APPENDIX_C, record=out["run"]))
    for mode in (Mode.closed, Mode.open):
        options = ReplayOptions(mode=mode, output=str(out[mode.value]))
        assert replay_recording(out["run"], options).error is None
    procs: list[Proc] = []
    try:
        port = free_udp_port()
        stats = folder / "mavsim.json"
        mavsim = start_mavsim(procs, port, stats)
        mission = write_mission(
            folder, "    return [api.executeBehavior('TAKE_OFF'), api.executeBehavior('LAND')]\n"
        )
        fly(FlightConfig(mission=mission, connect=f"udpin:127.0.0.1:{port}", record=out["fly"]))
        stop_mavsim(mavsim, stats)
    finally:
        for proc in procs:
            proc.kill()
    for name, bag in [
        ("turtle", TURTLE_LZ4),
        ("aerostack", AEROSTACK_BAG),
        ("mission_bag", short_mission().write(folder / "mission.bag")),
    ]:
        out[name] = folder / f"{name}.mcap"
        import_bag(bag, out[name])
    yield out


def _topics(path: Path) -> dict[str, tuple[str, dict[str, Any] | None, list[Any]]]:
    """Topic -> (schema name, JSON Schema, decoded messages); a ros1 channel's messages
    are kept undecoded."""
    topics: dict[str, tuple[str, dict[str, Any] | None, list[Any]]] = {}
    with open(path, "rb") as stream:
        for schema, channel, message in make_reader(stream).iter_messages():
            assert schema is not None
            is_json = channel.message_encoding == "json"
            entry = topics.setdefault(
                channel.topic, (schema.name, json.loads(schema.data) if is_json else None, [])
            )
            entry[2].append(json.loads(message.data) if is_json else message.data)
    return topics


def _log_panels(config: dict[str, Any]) -> list[str]:
    return [p["topicToRender"] for i, p in config.items() if i.startswith("RosOut!")]


@pytest.mark.parametrize(
    "kind", ["run", "closed", "open", "fly", "turtle", "aerostack", "mission_bag"]
)
def test_the_layout_for_a_recording_shows_what_it_holds(kinds: dict[str, Path], kind: str) -> None:
    path = kinds[kind]
    topics = _topics(path)
    content = content_for(open_session(path))
    config = foxglove_layout(content)["configById"]
    check_panels(config, topics, content.drone)  # every panel, every series shows something
    logs = _log_panels(config)
    # Every log of the session has its panel (a bag's rosout once: rosout_agg repeats it).
    session_logs = [t for t, (name, _, ms) in topics.items() if name == "foxglove.Log" and ms]
    ros_logs = [t for t, (name, _, ms) in topics.items() if name == "rosgraph_msgs/Log" and ms]
    assert [t for t in logs if t in session_logs] == session_logs
    assert len([t for t in logs if t in ros_logs]) == min(len(ros_logs), 1)
    capabilities = [p for i, p in config.items() if i == "StateTransitions!capabilities"]
    used = {m["name"] for m in topics.get("/drone1/capability_state", ("", None, []))[2]}
    assert {s["label"] for p in capabilities for s in p["paths"]} == used


def test_each_kind_gets_its_own_logs(kinds: dict[str, Path]) -> None:
    logs = {
        kind: _log_panels(foxglove_layout(content_for(open_session(path)))["configById"])
        for kind, path in kinds.items()
    }
    assert logs["run"] == logs["closed"] == ["/drone1/call_log", "/drone1/log"]
    # The generic layout's /drone1/log stays empty for an open-loop replay (the session
    # log is not replayed); a flight has one when the autopilot says something (mavsim's
    # EKF line), which the first test checks against the recording.
    assert logs["open"] == ["/drone1/call_log"]
    assert logs["fly"][0] == "/drone1/call_log"
    assert logs["turtle"] == ["/ros1/rosout"]
    assert logs["aerostack"] == ["/ros1/rosout"]
    assert logs["mission_bag"] == ["/drone1/call_log"]


def test_cli_for_a_recording_and_its_refusals(kinds: dict[str, Path], tmp_path: Path) -> None:
    target = tmp_path / "fly.json"
    result = CliRunner().invoke(
        app, ["layout", "--foxglove", "--for", str(kinds["fly"]), "-o", str(target)]
    )
    assert result.exit_code == 0, result.stderr
    assert target.read_text() == layout_text(content_for(open_session(kinds["fly"])))
    for path, message in [
        (ROS2_MCAP, "error: not an aeroexec recording (profile ros2)"),
        (tmp_path / "missing.mcap", "error: no such file"),
    ]:
        result = CliRunner().invoke(app, ["layout", "--foxglove", "--for", str(path)])
        assert result.exit_code == 2 and result.stdout == ""
        assert result.stderr.startswith(f"{path}: {message}") and result.stderr.count("\n") == 1
