"""`aeroexec view` conversion: write `.rrd` files headless and read them back with Rerun's
own reader (`rerun.chunk.RrdReader`), checking them against the source recordings as
read by aeroexec's reader and by the `mcap` library's."""

from __future__ import annotations

import json
import shutil
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pyarrow as pa
import pytest
from mcap.reader import make_reader
from rerun.chunk import RrdReader

from aeroexec.mission import APPENDIX_C, SessionConfig, simulate
from aeroexec.recording import open_recording, recording_info
from aeroexec.recording.reader import RecordedCall, RecordedTopic
from aeroexec.vehicles.world import FAULTS_WORLD, parse_world
from aeroexec.viz import Layout, recording_id_for, write_view

VIEW_MISSION = Path(__file__).resolve().parent / "fixtures" / "view" / "mission_view.py"
ROW_ID = "rerun.controls.RowId"


# -- recordings and reading back ----------------------------------------------------------
@pytest.fixture(scope="module")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """appendix_c (default world), and the view mission in the default world (`base`)
    and in the faults world (`faults`: a WRONG_PROGRESS, a PROCESS_FAILURE at start)."""
    folder = tmp_path_factory.mktemp("view_rec")
    out = {
        "appendix_c": folder / "appendix_c.mcap",
        "base": folder / "base.mcap",
        "faults": folder / "faults.mcap",
    }
    simulate(SessionConfig(mission=APPENDIX_C, record=out["appendix_c"]))
    simulate(SessionConfig(mission=VIEW_MISSION, record=out["base"]))
    simulate(SessionConfig(mission=VIEW_MISSION, world=FAULTS_WORLD, record=out["faults"]))
    return out


@dataclass
class Rrd:
    """An .rrd file's recording store: rows per entity (time-indexed ones in logging
    order, by row id) and static rows per entity."""

    rows: dict[str, list[dict[str, Any]]] = field(default_factory=dict)
    static: dict[str, list[dict[str, Any]]] = field(default_factory=dict)
    chunks: list[tuple[str, int, bool]] = field(default_factory=list)
    recording_ids: list[str] = field(default_factory=list)
    blueprints: int = 0

    def entities(self) -> set[str]:
        return set(self.rows) | set(self.static)

    def times(self, entity: str) -> list[int]:
        return [row["sim_time"] for row in self.rows.get(entity, [])]

    def values(self, entity: str, column: str) -> list[Any]:
        return [_single(row[column]) for row in self.rows.get(entity, [])]


def _single(value: Any) -> Any:
    return value[0] if isinstance(value, list) and len(value) == 1 else value


def read_rrd(path: Path) -> Rrd:
    reader = RrdReader(path)
    rrd = Rrd(
        recording_ids=[entry.recording_id for entry in reader.recordings()],
        blueprints=len(reader.blueprints()),
    )
    for chunk in reader.stream():
        rrd.chunks.append((chunk.entity_path, chunk.num_rows, chunk.is_static))
        batch = chunk.to_record_batch()
        columns: dict[str, list[Any]] = {}
        for name in batch.schema.names:
            column = batch.column(name)
            if pa.types.is_duration(column.type):
                column = column.cast(pa.int64())  # nanoseconds, exactly
            columns[name] = column.to_pylist()
        for i in range(chunk.num_rows):
            row = {name: values[i] for name, values in columns.items()}
            target = rrd.static if chunk.is_static else rrd.rows
            target.setdefault(chunk.entity_path, []).append(row)
    for rows in rrd.rows.values():
        rows.sort(key=lambda row: row[ROW_ID])
    return rrd


@pytest.fixture(scope="module")
def views(recordings: dict[str, Path], tmp_path_factory: pytest.TempPathFactory) -> dict[str, Rrd]:
    folder = tmp_path_factory.mktemp("view_rrd")
    out: dict[str, Rrd] = {}
    for name in ("appendix_c", "faults"):
        target = folder / f"{name}.rrd"
        write_view([recordings[name]], target)
        out[name] = read_rrd(target)
    target = folder / "diff.rrd"
    write_view([recordings["base"], recordings["faults"]], target)
    out["diff"] = read_rrd(target)
    return out


def _topics(path: Path, name: str) -> list[RecordedTopic]:
    return [
        r for r in open_recording(path).records() if isinstance(r, RecordedTopic) and r.name == name
    ]


def _calls(path: Path) -> list[RecordedCall]:
    return [r for r in open_recording(path).records() if isinstance(r, RecordedCall)]


def _mcap_count(path: Path, topic: str) -> int:
    """Count with the mcap library's own reader (independent of aeroexec's)."""
    with open(path, "rb") as f:
        return sum(1 for _ in make_reader(f).iter_messages(topics=[topic]))


# -- the entity tree ---------------------------------------------------------------------
def test_expected_entity_paths_exist(views: dict[str, Rrd]) -> None:
    entities = views["appendix_c"].entities()
    root = Layout()
    expected = {
        root.markers,
        root.object,
        root.vehicle,
        root.body,
        root.trajectory,
        root.trajectory_line,
        root.telemetry("battery"),
        root.telemetry("altitude"),
        root.telemetry("speed"),
        root.events,
        root.calls,
        root.mission,
        root.log,
        root.beliefs,
        *(
            root.behavior_active(b)
            for b in (
                "TAKE_OFF",
                "PAY_ATTENTION_TO_VISUAL_MARKERS",
                "GO_TO_POINT",
                "ROTATE",
                "LAND",
            )
        ),
        *(root.behavior_state(b) for b in ("TAKE_OFF", "GO_TO_POINT", "LAND")),
        root.capability("SELF_LOCALIZATION_BY_ODOMETRY"),
        root.capability("VISUAL_MARKERS_RECOGNITION"),
        root.process("droneOdometryStateEstimator"),
    }
    assert expected <= entities, sorted(expected - entities)
    assert "/events" in expected  # a single recording sits at the top of the tree
    # appendix_c has no refusal and no fault: no error rows at all
    assert root.errors not in entities


def test_only_recording_entities_no_wall_clock(views: dict[str, Rrd]) -> None:
    rrd = views["appendix_c"]
    for entity, rows in rrd.rows.items():
        for row in rows:
            assert "sim_time" in row, entity
            assert "log_time" not in row and "log_tick" not in row, entity


# -- counts against the source ----------------------------------------------------------
@pytest.mark.parametrize("name", ["appendix_c", "faults"])
def test_event_rows_equal_behavior_event_messages(
    name: str, recordings: dict[str, Path], views: dict[str, Rrd]
) -> None:
    events = _topics(recordings[name], "behavior_event")
    assert len(events) == _mcap_count(recordings[name], "/drone1/behavior_event") >= 7
    rrd = views[name]
    assert len(rrd.rows["/events"]) == len(events)
    assert rrd.times("/events") == [e.log_time_ns for e in events]
    texts = rrd.values("/events", "TextLog:text")
    for text, event in zip(texts, events, strict=True):
        assert text.startswith(f"{event.data['name']} #{event.data['uid']} {event.data['code']}")


def test_event_levels_follow_outcome(views: dict[str, Rrd]) -> None:
    rrd = views["faults"]
    by_text = dict(
        zip(
            rrd.values("/events", "TextLog:text"),
            rrd.values("/events", "TextLog:level"),
            strict=True,
        )
    )
    levels = {text.split(" ")[2].rstrip(":"): level for text, level in by_text.items()}
    assert levels["GOAL_ACHIEVED"] == "INFO"
    assert levels["WRONG_PROGRESS"] == "WARN"
    assert levels["PROCESS_FAILURE"] == "ERROR"


@pytest.mark.parametrize("name", ["appendix_c", "faults"])
def test_trajectory_has_one_point_per_vehicle_state(
    name: str, recordings: dict[str, Path], views: dict[str, Rrd]
) -> None:
    states = _topics(recordings[name], "vehicle/state")
    assert len(states) == _mcap_count(recordings[name], "/drone1/vehicle/state") > 100
    rrd = views[name]
    assert len(rrd.rows["/trajectory"]) == len(states)
    assert len(rrd.rows["/trajectory/line"]) == len(states)
    assert rrd.times("/trajectory") == [s.log_time_ns for s in states]
    points = rrd.values("/trajectory", "Points3D:positions")
    for point, state in zip(points, states, strict=True):
        assert point == pytest.approx(state.data["position"], abs=1e-5)
    # each line segment ends where its point is, and starts at the previous point
    segments = rrd.values("/trajectory/line", "LineStrips3D:strips")
    assert segments[5][0] == pytest.approx(points[4], abs=1e-6)
    assert segments[5][1] == pytest.approx(points[5], abs=1e-6)


def test_pose_is_a_transform_per_vehicle_state(
    recordings: dict[str, Path], views: dict[str, Rrd]
) -> None:
    # The pose comes from vehicle/state; it agrees with the frame transform the
    # recording carries for Foxglove (the same pose, derived by the recorder), after
    # the one at the first log time (the start pose, before the first state).
    start, *transforms = _topics(recordings["appendix_c"], "vehicle/transform")
    assert start.log_time_ns == 0 and start.data["translation"] == {"x": 0, "y": 0, "z": 0}
    rrd = views["appendix_c"]
    rows = rrd.rows["/vehicle"]
    assert (
        len(rows)
        == len(transforms)
        == _mcap_count(recordings["appendix_c"], "/drone1/vehicle/state")
    )
    assert rrd.times("/vehicle") == [p.log_time_ns for p in transforms]
    for row, message in zip(rows, transforms, strict=True):
        q, p = message.data["rotation"], message.data["translation"]
        assert _single(row["Transform3D:quaternion"]) == pytest.approx(
            [q["x"], q["y"], q["z"], q["w"]], abs=1e-6
        )
        assert _single(row["Transform3D:translation"]) == pytest.approx(
            [p["x"], p["y"], p["z"]], abs=1e-5
        )
    # appendix_c turns to -90 degrees: some pose has a non-identity rotation
    assert any(abs(_single(r["Transform3D:quaternion"])[2]) > 0.5 for r in rows)


# -- behavior intervals -----------------------------------------------------------------
def _transitions(rrd: Rrd, entity: str) -> list[tuple[int, float]]:
    """(time, value) where the 1/0 track changes value, starting from 0."""
    out: list[tuple[int, float]] = []
    current = 0.0
    for t, value in zip(rrd.times(entity), rrd.values(entity, "Scalars:scalars"), strict=True):
        if value != current:
            out.append((t, value))
            current = value
    return out


def _expected_transitions(path: Path) -> dict[str, list[tuple[int, float]]]:
    """Straight from the source, holding the whole file: each accepted activate_behavior
    call is 1 at its time, and its behavior_event (matched by uid, wherever it is in the
    file) is 0 at the event's time; activations in uid order."""
    started: dict[int, tuple[str, int]] = {}
    ended: dict[int, int] = {}
    for record in open_recording(path).records():
        if isinstance(record, RecordedCall) and record.service == "activate_behavior":
            if record.ok:
                started[record.response["uid"]] = (record.request["behavior"], record.log_time_ns)
        elif isinstance(record, RecordedTopic) and record.name == "behavior_event":
            ended[record.data["uid"]] = record.log_time_ns
    out: dict[str, list[tuple[int, float]]] = {}
    for uid in sorted(started):
        behavior, t = started[uid]
        edges = out.setdefault(behavior, [])
        edges.append((t, 1.0))
        if uid in ended:
            edges.append((max(t, ended[uid]), 0.0))
    return {behavior: _one_per_instant(edges) for behavior, edges in out.items()}


def _one_per_instant(pairs: list[tuple[int, float]]) -> list[tuple[int, float]]:
    """The view's rule: a change at or before the series' previous row goes 1 ns after it
    (a plot never holds two values at one time)."""
    out: list[tuple[int, float]] = []
    for t, value in pairs:
        if out and t <= out[-1][0]:
            t = out[-1][0] + 1
        out.append((t, value))
    return out


@pytest.mark.parametrize("name", ["appendix_c", "faults"])
def test_behavior_intervals_match_activations_and_events(
    name: str, recordings: dict[str, Path], views: dict[str, Rrd]
) -> None:
    expected = _expected_transitions(recordings[name])
    rrd = views[name]
    assert expected
    for behavior, edges in expected.items():
        assert _transitions(rrd, f"/behaviors/active/{behavior}") == edges, behavior


def test_plots_show_no_value_that_did_not_happen(
    recordings: dict[str, Path], views: dict[str, Rrd]
) -> None:
    """Rerun's plot averages rows that share a time (the 0.5 levels once seen): every
    series has one row per sim_time, only values the session had, and keeps extremes,
    not averages, when zoomed out (aggregation MinMax)."""
    rrd = views["appendix_c"]
    happened: dict[str, set[float]] = {}
    for message in _topics(recordings["appendix_c"], "list_of_active_capabilities"):
        for c in message.data["capabilities"]:
            happened.setdefault(c["name"], {0.0}).add(float(c["references"]))
    series = sorted(e for e, rows in rrd.rows.items() if "Scalars:scalars" in rows[0])
    behaviors = [e for e in series if e.startswith("/behaviors/active/")]
    capabilities = [e for e in series if e.startswith("/capabilities/")]
    assert len(behaviors) == 5 and len(capabilities) == len(happened) >= 3
    for entity in series:
        times = rrd.times(entity)
        assert times == sorted(set(times)), entity  # strictly increasing: one row per time
        values = set(rrd.values(entity, "Scalars:scalars"))
        if entity in behaviors:
            assert values == {0.0, 1.0}, entity
        elif entity in capabilities:
            assert values <= happened[entity.rsplit("/", 1)[1]], entity
        style = rrd.static[entity][0]
        assert _single(style["SeriesLines:aggregation_policy"]) == 5, entity  # MinMax
    # GO_TO_POINT #3 ends and #4 starts at 4.0 s: the drop and the rise are both there.
    rows = list(
        zip(
            rrd.times("/behaviors/active/GO_TO_POINT"),
            rrd.values("/behaviors/active/GO_TO_POINT", "Scalars:scalars"),
            strict=True,
        )
    )
    assert (4_000_000_000, 0.0) in rows and (4_000_000_001, 1.0) in rows


def test_preempted_and_failed_at_start_behaviors(views: dict[str, Rrd]) -> None:
    rrd = views["faults"]
    # GO_TO_POINT #3 is preempted at 2.3 s the instant it starts; the next GO_TO_POINT
    # starts at 2.8 s: up, down, up at the right times, not merged into one interval
    assert _transitions(rrd, "/behaviors/active/GO_TO_POINT")[:3] == [
        (2_300_000_000, 1.0),
        (2_300_000_001, 0.0),  # the same instant: the drop shows 1 ns after the rise
        (2_800_000_000, 1.0),
    ]
    # LAND fails inside the call that starts it: its end event is written before the
    # activate_behavior call, and the track still ends at 0
    assert _transitions(rrd, "/behaviors/active/LAND") == [
        (13_000_000_000, 1.0),
        (13_000_000_001, 0.0),
    ]
    assert rrd.values("/behaviors/active/LAND", "Scalars:scalars")[-1] == 0.0


def test_behavior_state_lanes_label_each_activation(views: dict[str, Rrd]) -> None:
    rrd = views["faults"]
    states = rrd.values("/behaviors/state/GO_TO_POINT", "StateChange:state")
    assert states == [
        "#3 coordinates=[-2, 0, 1]",
        "",
        "#5 coordinates=[2, 3, 1.5]",
        "",
        "#6 coordinates=[0, 0, 1]",
        "",
    ]


def test_step_series_reach_the_end_of_the_session(
    recordings: dict[str, Path], views: dict[str, Rrd]
) -> None:
    end = recording_info(recordings["appendix_c"]).end_ns
    rrd = views["appendix_c"]
    for entity in ("/behaviors/active/TAKE_OFF", "/capabilities/SELF_LOCALIZATION_BY_ODOMETRY"):
        assert rrd.times(entity)[-1] == end, entity
    style = rrd.static["/behaviors/active/TAKE_OFF"][0]
    assert _single(style["SeriesLines:interpolation_mode"]) == 2  # StepAfter


# -- capabilities, errors, calls --------------------------------------------------------
def _changes(pairs: list[tuple[int, float]]) -> list[tuple[int, float]]:
    out: list[tuple[int, float]] = []
    for t, value in pairs:
        if (out[-1][1] if out else 0) != value:
            out.append((t, value))
    return out


def test_capability_counts_follow_the_published_lists(
    recordings: dict[str, Path], views: dict[str, Rrd]
) -> None:
    rrd = views["appendix_c"]
    messages = _topics(recordings["appendix_c"], "list_of_active_capabilities")
    names = {c["name"] for m in messages for c in m.data["capabilities"]}
    assert len(names) >= 3
    for name in names:
        entity = f"/capabilities/{name}"
        expected = _one_per_instant(
            _changes(
                [
                    (
                        m.log_time_ns,
                        {c["name"]: c["references"] for c in m.data["capabilities"]}.get(name, 0),
                    )
                    for m in messages
                ]
            )
        )
        got = _changes(
            list(zip(rrd.times(entity), rrd.values(entity, "Scalars:scalars"), strict=True))
        )
        assert got == expected, name
        assert any(count == 0 for _, count in expected) or name == "SELF_LOCALIZATION_BY_ODOMETRY"


def test_rejected_activation_and_fault_in_errors(
    recordings: dict[str, Path], views: dict[str, Rrd]
) -> None:
    rrd = views["faults"]
    rejected = [c for c in _calls(recordings["faults"]) if c.service == "activate_behavior"]
    rejected = [c for c in rejected if not c.ok]
    assert len(rejected) == 1
    rows = rrd.rows["/errors"]
    texts = [_single(r["TextLog:text"]) for r in rows]
    levels = [_single(r["TextLog:level"]) for r in rows]
    assert texts[0] == "REJECTED GO_TO_POINT coordinates=[1, 1, 1]: GO_TO_POINT: not flying"
    assert levels[0] == "WARN"
    assert rows[0]["seq"] == rejected[0].seq
    assert "vehicle fault: stuck_motor" in texts
    assert levels[texts.index("vehicle fault: stuck_motor")] == "ERROR"


def _depths(calls: list[RecordedCall]) -> dict[int, int]:
    parents = {c.seq: c.parent_seq for c in calls}
    depths: dict[int, int] = {}
    for seq in parents:
        depth, parent = 0, parents[seq]
        while parent is not None:
            depth, parent = depth + 1, parents.get(parent)
        depths[seq] = depth
    return depths


def test_call_tree_rows_in_start_order_indented_by_depth(
    recordings: dict[str, Path], views: dict[str, Rrd]
) -> None:
    calls = _calls(recordings["appendix_c"])
    rrd = views["appendix_c"]
    rows = rrd.rows["/calls"]
    assert len(rows) == len(calls)
    seqs = [row["seq"] for row in rows]
    assert seqs == sorted(c.seq for c in calls)  # each tree in start order, trees in order
    depths = _depths(calls)
    by_seq = {c.seq: c for c in calls}
    for row in rows:
        text = _single(row["TextLog:text"])
        indent = len(text) - len(text.lstrip(" "))
        assert indent == 2 * depths[row["seq"]], text
        assert f"[{row['seq']}] " in text
        assert row["sim_time"] == by_seq[row["seq"]].log_time_ns
    assert max(depths.values()) >= 3  # the tree really is nested


def test_markers_come_from_the_world_attachment(
    recordings: dict[str, Path], views: dict[str, Rrd]
) -> None:
    attachment = open_recording(recordings["appendix_c"]).attachment("world.yaml")
    assert attachment is not None
    world = parse_world(attachment.text)
    static = views["appendix_c"].static["/world/markers"][0]
    assert static["Boxes3D:centers"] == [pytest.approx(list(m.position)) for m in world.markers]
    assert static["Boxes3D:labels"] == [f"marker {m.id}" for m in world.markers]


# -- two recordings ---------------------------------------------------------------------
def test_two_recordings_side_by_side(recordings: dict[str, Path], views: dict[str, Rrd]) -> None:
    rrd = views["diff"]
    entities = rrd.entities()
    for root in ("base", "new"):
        layout = Layout(root)
        assert {layout.events, layout.trajectory, layout.vehicle, layout.markers} <= entities
        assert layout.behavior_active("GO_TO_POINT") in entities
    assert "/events" not in entities and "/trajectory" not in entities
    base_events = _topics(recordings["base"], "behavior_event")
    new_events = _topics(recordings["faults"], "behavior_event")
    assert len(rrd.rows["/base/events"]) == len(base_events)
    assert len(rrd.rows["/new/events"]) == len(new_events)
    # aligned on sim_time: both sessions' first state is at 0.1 s, and the runs diverge
    # where the faults world's motor seizes (8 s)
    assert rrd.times("/base/trajectory")[0] == rrd.times("/new/trajectory")[0] == 100_000_000
    new_texts = rrd.values("/new/events", "TextLog:text")
    base_texts = rrd.values("/base/events", "TextLog:text")
    assert any("WRONG_PROGRESS" in t for t in new_texts)
    assert not any("WRONG_PROGRESS" in t for t in base_texts)
    assert len(rrd.recording_ids) == 1  # one Rerun recording holding both sessions


def test_blueprint_opens_on_the_flight_and_behavior_views(views: dict[str, Rrd]) -> None:
    assert views["appendix_c"].blueprints == 1


def test_blueprint_content(recordings: dict[str, Path], tmp_path: Path) -> None:
    target = tmp_path / "one.rrd"
    write_view([recordings["appendix_c"]], target)
    reader = RrdReader(target)
    views: dict[str, tuple[str, str]] = {}
    timeline = None
    for chunk in reader.stream(store=reader.blueprints()[0]):
        batch = chunk.to_record_batch()
        names = batch.schema.names
        if "ViewBlueprint:class_identifier" in names:
            kind = batch.column("ViewBlueprint:class_identifier").to_pylist()[0][0]
            title = batch.column("ViewBlueprint:display_name").to_pylist()[0][0]
            origin = batch.column("ViewBlueprint:space_origin").to_pylist()[0][0]
            views[title] = (kind, origin)
        if "TimePanelBlueprint:timeline" in names:
            timeline = batch.column("TimePanelBlueprint:timeline").to_pylist()[0][0]
    assert views["Flight"] == ("3D", "/")
    assert views["Behaviors"][0] == "StateTimeline"
    assert views["Capability references"] == ("TimeSeries", "/capabilities")
    assert views["Behavior active (1/0)"] == ("TimeSeries", "/behaviors/active")
    assert views["Events & errors"][0] == "TextLog"
    assert views["Service calls"] == ("TextLog", "/calls")
    assert timeline == "sim_time"


# -- identity and determinism ------------------------------------------------------------
def _content(rrd: Rrd) -> tuple[Counter[tuple[str, int, bool]], dict[str, list[Any]]]:
    """Everything but the row ids (which carry the time they were made)."""
    rows = {
        entity: [{k: v for k, v in row.items() if k != ROW_ID} for row in entity_rows]
        for entity, entity_rows in rrd.rows.items()
    }
    return Counter(rrd.chunks), rows


def test_same_recording_twice_gives_the_same_chunks(
    recordings: dict[str, Path], tmp_path: Path
) -> None:
    first, second = tmp_path / "1.rrd", tmp_path / "2.rrd"
    a = write_view([recordings["faults"]], first)
    b = write_view([recordings["faults"]], second)
    assert a.recording_id == b.recording_id
    one, two = read_rrd(first), read_rrd(second)
    assert _content(one) == _content(two)

    def strip(static: dict[str, list[dict[str, Any]]]) -> dict[str, list[dict[str, Any]]]:
        return {
            e: [{k: v for k, v in r.items() if k != ROW_ID} for r in rows]
            for e, rows in static.items()
        }

    assert strip(one.static) == strip(two.static)
    # Byte equality does not hold: Rerun stamps every chunk and row id (TUIDs) with the
    # time they were created, and gives the embedded blueprint a fresh id.
    assert first.read_bytes() != second.read_bytes()


def test_recording_id_is_derived_from_content(recordings: dict[str, Path], tmp_path: Path) -> None:
    copy = tmp_path / "copy.mcap"
    shutil.copyfile(recordings["base"], copy)
    assert recording_id_for([copy]) == recording_id_for([recordings["base"]])
    assert recording_id_for([recordings["faults"]]) != recording_id_for([recordings["base"]])
    pair = recording_id_for([recordings["base"], recordings["faults"]])
    assert pair != recording_id_for([recordings["faults"], recordings["base"]])
    target = tmp_path / "copy.rrd"
    report = write_view([copy], target)
    assert read_rrd(target).recording_ids == [report.recording_id]


def test_incomplete_recording_is_shown_up_to_the_damage(
    recordings: dict[str, Path], tmp_path: Path
) -> None:
    data = recordings["appendix_c"].read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    states = _topics(cut, "vehicle/state")
    assert 0 < len(states) < len(_topics(recordings["appendix_c"], "vehicle/state"))
    report = write_view([cut], tmp_path / "cut.rrd")
    source = report.sources[0]
    assert not source.complete and source.problem
    rrd = read_rrd(tmp_path / "cut.rrd")
    assert len(rrd.rows["/trajectory"]) == len(states)


def test_the_first_release_recording_still_converts(tmp_path: Path) -> None:
    """recordings/appendix_c-v0.1.0.mcap: top-level calls with `"parent_seq": null` and
    the old `vehicle/pose` channel: the same call tree and pose track as new files."""
    old = Path(__file__).resolve().parent.parent / "recordings" / "appendix_c-v0.1.0.mcap"
    with open(old, "rb") as stream:
        raw_roots = sum(
            1
            for schema, _, message in make_reader(stream).iter_messages()
            if schema is not None
            and schema.name == "aeroexec.ServiceCall"
            and json.loads(message.data)["parent_seq"] is None
        )
    calls = _calls(old)
    assert raw_roots > 0
    assert sum(c.parent_seq is None for c in calls) == raw_roots
    write_view([old], tmp_path / "old.rrd")
    rrd = read_rrd(tmp_path / "old.rrd")
    depths = _depths(calls)
    assert max(depths.values()) >= 3
    for row in rrd.rows["/calls"]:
        text = _single(row["TextLog:text"])
        assert len(text) - len(text.lstrip(" ")) == 2 * depths[row["seq"]]
    assert len(rrd.rows["/vehicle"]) == len(_topics(old, "vehicle/state"))
