"""Properties monitored online (`run --spec`): the same verdicts as `check` on the
recording of the same flight, and actions that end the flight the way they say."""

from __future__ import annotations

import contextlib
import io
import math
import random
from pathlib import Path

import numpy as np
import pytest

from aeroexec.mission.script import Ending
from aeroexec.mission.session import SessionConfig, simulate
from aeroexec.properties.check import VIOLATED, check_recording
from aeroexec.properties.monitor import PropertyMonitor
from aeroexec.properties.spec import load_properties
from aeroexec.recording import open_recording

ROOT = Path(__file__).resolve().parent.parent
APPENDIX_C = ROOT / "missions" / "appendix_c.py"
FAULTS_WORLD = ROOT / "aeroexec" / "data" / "worlds" / "faults.yaml"
SPEC = """\
properties:
  - name: ceiling
    formula: always(altitude <= 1.4)
  - name: lands_soon
    formula: always((command_LAND >= 1) implies eventually[0:2](landed >= 1))
  - name: took_off_first
    formula: always((active_GO_TO_POINT >= 1) implies once(active_TAKE_OFF >= 1))
  - name: markers_with_odometry
    formula: always((active_PAY_ATTENTION_TO_VISUAL_MARKERS >= 1) implies
      (capability_SELF_LOCALIZATION_BY_ODOMETRY >= 1))
  - name: eventually_far
    formula: eventually(distance_home >= 6)
"""
FENCE = """\
properties:
  - name: geofence
    description: stay within 4 m of home
    formula: always(distance_home <= 4)
    action: {action}
"""


def _run(tmp: Path, name: str, specs: list[str], world: Path | None = None, every: float = 0.5):
    monitor = PropertyMonitor(load_properties(specs), check_every_s=every)
    out = tmp / f"{name}.mcap"
    with contextlib.redirect_stdout(io.StringIO()):
        result = simulate(
            SessionConfig(mission=APPENDIX_C, world=world, record=out), observers=[monitor]
        )
    return monitor, result, out


def _same(verdicts_a, verdicts_b) -> None:
    a = [(v.name, v.status, v.robustness, v.interval_s, v.missing) for v in verdicts_a]
    b = [(v.name, v.status, v.robustness, v.interval_s, v.missing) for v in verdicts_b]
    assert a == b


@pytest.mark.parametrize("world", [None, FAULTS_WORLD], ids=["default", "faults"])
def test_online_and_offline_verdicts_of_one_flight_are_identical(tmp_path, world) -> None:
    spec = tmp_path / "spec.yaml"
    spec.write_text(SPEC, encoding="utf-8")
    specs = ["aeroexec:safety", str(spec)]
    monitor, _, recording = _run(tmp_path, "flight", specs, world)
    offline = check_recording(recording, load_properties(specs)).verdicts
    _same(monitor.verdicts, offline)
    # Not trivially: both kinds of verdict are there.
    assert {v.status for v in offline} >= {"held", VIOLATED}


def test_a_geofence_with_land_ends_the_flight_at_the_fence(tmp_path) -> None:
    spec = tmp_path / "fence.yaml"
    spec.write_text(FENCE.format(action="land"), encoding="utf-8")
    monitor, result, recording = _run(tmp_path, "fenced", [str(spec), "aeroexec:safety"])
    # Appendix C crosses 4 m from home at 6.5 s on its way to (3, 5.5).
    assert monitor.stopped_at_s == pytest.approx(6.5)
    assert result.outcome.ending is Ending.STOPPED
    assert result.assurance[-1] == "landing"
    assert not result.final_state.flying and not result.final_state.armed
    x, y, _ = result.final_state.position
    assert 4.0 < (x * x + y * y) ** 0.5 < 4.6  # it landed where it was, just past the fence
    rec = open_recording(recording)
    end = rec.metadata["aeroexec_end"]
    assert end["reason"] == "property"
    assert "geofence violated at 6.50 s" in end["detail"]
    published = [r for r in rec.records() if getattr(r, "name", "") == "properties"]
    early = published[0]
    assert early.data["status"] == VIOLATED and early.data["t_s"] == 6.5
    assert early.data["action"] == "land"
    assert early.log_time_ns <= 7_000_000_000  # seen within the check period
    logs = [r.data for r in rec.records() if getattr(r, "name", "") == "log"]
    assert any(d["level"] == 4 and d["name"] == "property:geofence" for d in logs)
    # After the landing, the safety set holds on the recording, offline as online.
    offline = check_recording(recording, load_properties([str(spec), "aeroexec:safety"]))
    _same(monitor.verdicts, offline.verdicts)
    assert [v.name for v in offline.violated] == ["geofence"]


@pytest.mark.parametrize(
    "body",
    [
        "command_GO_TO_POINT <= 0",  # judged tick by tick
        "historically[0:0.2](command_GO_TO_POINT <= 0)",  # judged on arrays, every 0.5 s
    ],
)
def test_a_command_is_judged_on_the_tick_it_is_issued(tmp_path, body) -> None:
    # A mission command comes after its tick's vehicle state: a tick is judged when it is
    # over, so the command's one-tick pulse is seen online where check sees it (judged
    # every tick, as `fly` does, a tick judged at its vehicle state would miss it).
    spec = tmp_path / "spec.yaml"
    spec.write_text(
        f"properties:\n  - name: no_go_to\n    formula: always({body})\n    action: abort\n",
        encoding="utf-8",
    )
    monitor, result, recording = _run(tmp_path, "commanded", [str(spec)], every=0.1)
    commands = [
        r
        for r in open_recording(recording).records()
        if getattr(r, "name", "") == "mission/command" and r.data["behavior"] == "GO_TO_POINT"
    ]
    issued_s = commands[0].log_time_ns / 1e9
    assert monitor.stopped_at_s == pytest.approx(issued_s)
    assert result.outcome.ending is Ending.STOPPED
    [offline] = check_recording(recording, load_properties([str(spec)])).verdicts
    assert offline.interval_s[0] == monitor.stopped_at_s
    _same(monitor.verdicts, [offline])


def test_rtl_returns_home_and_lands_hold_keeps_flying_abort_stops(tmp_path) -> None:
    ends = {}
    for action in ("rtl", "hold", "abort"):
        spec = tmp_path / f"{action}.yaml"
        spec.write_text(FENCE.format(action=action), encoding="utf-8")
        _, result, _ = _run(tmp_path, action, [str(spec)])
        ends[action] = result
    home = ends["rtl"].final_state
    assert not home.flying
    assert (home.position[0] ** 2 + home.position[1] ** 2) ** 0.5 < 0.3
    assert ends["hold"].final_state.flying and ends["hold"].assurance[-1] == "holding"
    assert ends["abort"].final_state.flying
    assert ends["abort"].duration_s < ends["hold"].duration_s


def test_an_action_needs_a_property_that_can_be_judged_during_the_flight() -> None:
    from aeroexec.errors import PropertyError
    from aeroexec.properties.spec import parse_properties

    with pytest.raises(PropertyError) as caught:
        parse_properties(
            "properties:\n  - name: a\n    formula: eventually(landed >= 1)\n    action: land\n",
            "a.yaml",
        )
    assert str(caught.value.mark) == "a.yaml:4:13"


def test_a_window_is_what_the_whole_gives_for_those_ticks(tmp_path) -> None:
    # The online check's windows against the offline extraction, on a real flight.
    from aeroexec.properties.check import SERVICES, TOPICS, _inside
    from aeroexec.properties.signals import SIGNALS, SignalBuilder

    _, _, recording = _run(tmp_path, "flight", ["aeroexec:safety"])
    builder = SignalBuilder(None)
    for record in open_recording(recording).records():
        name = getattr(record, "name", None)
        if name is None and record.service in SERVICES:
            builder.call(record.service, record.log_time_ns, record.request, record.response)
        elif name in TOPICS:
            builder.topic(name, record.log_time_ns, record.data)
    names = [s.name for s in SIGNALS if s.name not in ("incompatible", "end")] + [
        "active_GO_TO_POINT",
        "capability_SELF_LOCALIZATION_BY_ODOMETRY",
        "command_LAND",
        "fault_stuck_motor",
    ]
    for start in (0, 1, 23, 40, 93, builder.last_sample):
        whole = builder.finish(start, final=False)
        window = builder.window(start, names)
        assert window is not None
        for name in names:
            assert window[name].tolist() == whole.get(name).tolist(), (start, name)
    assert _inside("/drone1/vehicle/state") == "vehicle/state"


# -- judged by row: the same stops as judged when ticks are over ---------------------------
def _states(rng: random.Random) -> list:
    """Vehicle states (and some mission commands) with what a live vehicle or a bag can
    send: several states in one tick, ticks without one, states that are malformed or not
    numbers, ints and booleans, positions longer than 3, a state at the fence followed
    in the same tick by one inside it, a battery that falls."""
    from aeroexec.executive.messages import TopicRecord

    records = []
    t_ns, x, battery = 0, 0.0, 1.0
    for _ in range(rng.randrange(20, 120)):
        t_ns += rng.choice([0, 30_000_000, 100_000_000, 100_000_000, 350_000_000])
        x += rng.uniform(-0.5, 0.5)
        battery -= rng.uniform(0.0, 0.02)
        z = rng.choice([1.5, 2, 0.0, 3.9]) if rng.random() > 0.02 else 4.1
        position: list = [x, rng.uniform(-1, 1), z]
        vx = rng.uniform(-1.5, 1.5) if rng.random() > 0.02 else 3.0
        velocity: list = [vx, 0.0, rng.choice([0.0, 1])]
        data: dict = {"position": position, "velocity": velocity, "battery": battery}
        flying = rng.choice([True, 1]) if rng.random() > 0.02 else False
        data |= {"flying": flying, "armed": rng.random() > 0.02, "fault": ""}
        odd = rng.random()
        if odd < 0.04:
            del data["velocity"]  # malformed: no sample
        elif odd < 0.08:
            position[1] = None  # not a number
        elif odd < 0.1:
            position.append(7.0)  # longer than 3
        elif odd < 0.12:
            data["battery"] = "low"
        elif odd < 0.14:  # text of a number is no number either (the builder drops it)
            data[rng.choice(["battery", "flying", "armed"])] = "0.9"
            position[2] = rng.choice([position[2], "4"])
        records.append(TopicRecord("vehicle/state", data, t_ns))
        if rng.random() < 0.08:
            # Beyond the fence, then (mostly) back inside within the same tick.
            out = {**data, "position": [9.0, 0.0, 1.0]}
            records.append(TopicRecord("vehicle/state", out, t_ns))
            back = {**data, "position": [0.5, 0.0, 1.0]}
            if rng.random() < 0.9:
                records.append(TopicRecord("vehicle/state", back, t_ns + 10_000_000))
        if rng.random() < 0.1:
            records.append(TopicRecord("mission/command", {"behavior": "LAND"}, t_ns))
    return records


def test_states_fed_in_batches_give_the_signals_of_states_fed_one_by_one() -> None:
    # `SignalBuilder.vehicle_states` takes the common state straight into the table and
    # any other through `vehicle_state`: on every kind of state (faults that come and
    # go, a battery that falls below the low level, an import's defaults, stamps that
    # go back, a first state that is odd), in batches of any size, the same signals.
    from aeroexec.properties.signals import SignalBuilder

    faults = ["", "", "", "link_lost", "stuck_motor:2", None, "mode_changed"]
    for seed in range(80):
        rng = random.Random(seed)
        records = [r for r in _states(rng) if r.topic == "vehicle/state"]
        for record in records:
            data = record.data
            if rng.random() < 0.1:
                data["fault"] = rng.choice(faults)
            if rng.random() < 0.03:
                data["defaulted"] = rng.choice([["armed"], [], ["fault"]])
            if isinstance(data.get("battery"), float) and rng.random() < 0.1:
                data["battery"] = rng.choice([0.1, 0.3, math.nan])
        if rng.random() < 0.3:
            records.insert(2, type(records[0])("vehicle/state", dict(records[0].data), 0))
        if rng.random() < 0.2:  # a first state that makes no sample
            records.insert(0, type(records[0])("vehicle/state", {"position": [0, 0, 0]}, 0))
        one, batched = SignalBuilder(None), SignalBuilder(None)
        for record in records:
            one.vehicle_state(record.log_time_ns, record.data)
        at = 0
        while at < len(records):
            size = rng.choice([1, 2, 5, 64])
            batched.vehicle_states(records[at : at + size])
            at += size
        # repr: the rows hold NaN where a state's value was null (nan != nan)
        assert repr((batched.home_row, batched.last_row)) == repr((one.home_row, one.last_row))
        mine, theirs = batched.finish(), one.finish()
        assert (mine.length, mine.sources, mine.defaulted) == (
            theirs.length,
            theirs.sources,
            theirs.defaulted,
        )
        assert mine.values.keys() == theirs.values.keys(), seed
        for name, column in mine.values.items():
            assert np.array_equal(column, theirs.values[name], equal_nan=True), (seed, name)


@pytest.mark.parametrize(
    "body",
    [
        "distance_home <= {r}",
        "{r} >= distance_home",
        "altitude < 4",
        "battery >= {b}",
        "speed <= 2.5",
        "landed <= 0",
        "1 <= armed",
    ],
)
def test_a_property_judged_by_row_stops_where_ticks_judged_when_over_stop(body) -> None:
    # A vehicle signal against a number is judged on each state as it comes
    # (`Formula.threshold`); the same test written so it is not one of those shapes is
    # judged on each tick's values once the tick is over. Both must stop at the same
    # tick, on any sequence of states; and the signals the monitor collects (states fed
    # in batches) must be those of a builder fed each message as it comes.
    from aeroexec.executive.messages import TopicRecord
    from aeroexec.properties.signals import SignalBuilder
    from aeroexec.properties.spec import PropertySet, parse_properties

    stops = by_row_states = states = 0
    for seed in range(60):
        rng = random.Random(seed)
        text = body.format(r=rng.choice([2, 3.5, 6]), b=rng.choice([0.5, 0.8, 0.95]))
        every = rng.choice([0.1, 0.5])
        by_row, by_tick = (
            PropertyMonitor(
                PropertySet(
                    tuple(
                        parse_properties(
                            f"properties:\n  - name: p\n    formula: 'always({formula})'\n"
                            "    action: land\n",
                            "p.yaml",
                        )
                    ),
                    ("p.yaml",),
                ),
                check_every_s=every,
            )
            for formula in (text, f"({text}) and ({text})")
        )
        assert by_row._row_able and not by_tick._row_able
        records = _states(rng)
        # A message well after the last: the ticks judged on arrays are judged too (a
        # state that is not numbers leaves a tick to them).
        last = records[-1].log_time_ns + 2_000_000_000
        records.append(TopicRecord("mission/command", {"behavior": "LAND"}, last))
        whole = SignalBuilder(None)
        for record in records:
            for monitor in (by_row, by_tick):
                monitor.on_topic(record)
            if by_row.stopped_by is None and record.topic == "vehicle/state":
                states += 1
                by_row_states += by_row._state_holds is not None
            whole.topic(record.topic, record.log_time_ns, record.data)
        assert by_row.early == by_tick.early, (seed, text)
        assert by_row.stopped_at_s == by_tick.stopped_at_s
        stops += by_row.stopped_by is not None
        mine, theirs = by_row.builder.finish(), whole.finish()
        assert mine.length == theirs.length
        assert mine.values.keys() == theirs.values.keys()
        for name, column in mine.values.items():  # NaN where a state is not numbers
            assert np.array_equal(column, theirs.values[name], equal_nan=True), name
    assert 0 < stops < 60  # flights that break it, and flights that keep it
    assert by_row_states > states / 2  # most states before a stop judged by row


def test_a_state_test_is_the_row_value_test() -> None:
    # `signals.state_holds` judges a state before the builder has it: the same floats as
    # `row_value` on the row the builder makes of that state; all tests in one call hold
    # where each does.
    import operator

    from aeroexec.properties.signals import ROW_SIGNALS, SignalBuilder, row_value, state_holds

    rng = random.Random(7)
    for _ in range(300):
        builder = SignalBuilder(None)
        states = []
        for tick in range(2):
            state = {
                "position": [rng.choice([rng.uniform(-9, 9), 3, True]) for _ in range(3)],
                "velocity": [rng.choice([rng.uniform(-3, 3), -1, False]) for _ in range(3)],
                "battery": rng.choice([rng.random(), 1]),
                "flying": rng.choice([True, False]),
            }
            if rng.random() < 0.5:
                state["armed"] = rng.choice([True, False, 0])
            if rng.random() < 0.2:
                state["position"].append(5.5)
            states.append(state)
            assert builder.vehicle_state(tick * 100_000_000, state)
        first, row = builder.home_row, builder.last_row
        assert first is not None and row is not None
        tests, verdicts = [], []
        for name in sorted(ROW_SIGNALS):
            # Bounds about the value itself too: a geofence's square inside its circle
            # (`state_holds`) must never hold where the distance does not.
            value = row_value(name, row, first)
            near = value * rng.choice([1.0, 0.99, 0.71, 0.7, 1.01]) if math.isfinite(value) else 1
            bounds = [0.0, 1.0, rng.uniform(-5, 5), rng.uniform(0, 30), near, math.inf, 1e300]
            bound = rng.choice([*bounds, math.nan])
            for op in (
                operator.le,
                operator.lt,
                operator.gt,
                operator.ge,
                operator.eq,
                operator.ne,
            ):
                expected = op(row_value(name, row, first), bound)
                assert state_holds([(name, op, bound)], first)(states[-1]) == expected, name
                tests.append((name, op, bound))
                verdicts.append(expected)
        picked = rng.sample(range(len(tests)), 3)
        together = state_holds([tests[i] for i in picked], first)(states[-1])
        assert together == all(verdicts[i] for i in picked)
        # An import's guess is judged the general way, whatever the values; so is text
        # of a number, which the builder drops (a velocity's too).
        assert not state_holds([], first)({**states[-1], "defaulted": ["armed"]})
        with pytest.raises(TypeError):
            state_holds([("speed", operator.le, 5.0)], first)({"velocity": ["1.5", 0, 0]})
    # A geofence on the diagonal, from well inside to just outside its circle.
    home = (0, 1e3, -2e3, 0, 0, 0, 0, 1, 1, 1)
    for bound in (0.5, 50.0, 1e5, 1e160):
        for test in (operator.le, operator.lt):
            holds = state_holds([("distance_home", test, bound)], home)
            for share in (0.5, 0.69, 0.7, 0.7071, 0.7072, 0.71, 0.75, 0.9, 1.0):
                x, y = 1e3 + share * bound, -2e3 - share * bound
                state = {"position": [x, y, 1.0]}
                row = (0, x, y, 1.0, 0, 0, 0, 1, 1, 1)
                assert holds(state) == test(row_value("distance_home", row, home), bound)


# -- fly --spec, against MavSim (the SITL flight is in test_sitl_flights.py) ----------------
FAR = (
    "    api.executeBehavior('TAKE_OFF')\n"
    "    api.executeBehavior('GO_TO_POINT', coordinates=[0, 12, 1])\n"
    "    api.executeBehavior('LAND')\n"
)


def test_fly_spec_lands_at_the_geofence_and_the_verdicts_match_check(tmp_path) -> None:
    from live_helpers import free_udp_port, mavsim_thread, write_mission

    from aeroexec.mission.live import FlightConfig, fly

    spec = tmp_path / "fence.yaml"
    spec.write_text(FENCE.format(action="land"), encoding="utf-8")
    props = load_properties([str(spec), "aeroexec:safety"])
    monitor = PropertyMonitor(props, check_every_s=0.1)  # as fly --spec judges: every tick
    port = free_udp_port()
    out = tmp_path / "flight.mcap"
    with mavsim_thread(f"udpout:127.0.0.1:{port}", speed_factor=2.0) as sim:
        result = fly(
            FlightConfig(
                mission=write_mission(tmp_path, FAR),
                connect=f"udpin:127.0.0.1:{port}",
                record=out,
            ),
            observers=[monitor],
        )
        final = sim.stats()["final"]
    assert result.outcome.ending is Ending.STOPPED
    assert monitor.stopped_by is not None and monitor.stopped_by.name == "geofence"
    assert result.ending is not None and result.ending.down
    assert any(a.startswith("switched to LAND") for a in result.ending.actions)
    assert final["mode"] == "LAND" and not final["armed"]
    # It landed at the fence, not at the mission's target 12 m away: past it by what it
    # flies from the crossing to the stop (a tick is judged once over, at the next one's
    # vehicle state, and the stop comes at the step after: two ticks, 0.2 s of wall time
    # and 0.4 s of MavSim's, which runs at twice its speed), then its braking.
    assert 4.0 < math.hypot(*final["position"][:2]) < 7.0
    published = [
        r.data for r in open_recording(out).records() if getattr(r, "name", "") == "properties"
    ]
    assert published[0]["property"] == "geofence" and published[0]["action"] == "land"
    assert published[0]["t_s"] == monitor.stopped_at_s
    offline = check_recording(out, props)
    _same(monitor.verdicts, offline.verdicts)
    assert [v.name for v in offline.violated] == ["geofence"]


# -- the viewers ---------------------------------------------------------------------------
def test_violations_show_in_rerun_as_an_error_and_a_lane(tmp_path) -> None:
    from test_view import read_rrd

    from aeroexec.viz import write_view

    spec = tmp_path / "fence.yaml"
    spec.write_text(FENCE.format(action="land"), encoding="utf-8")
    _, _, recording = _run(tmp_path, "fenced", [str(spec)])
    target = tmp_path / "fenced.rrd"
    write_view([recording], target)
    rrd = read_rrd(target)
    lane = "/properties/geofence"
    # Violated from 6.5 s (seen during the flight) to the end of the landing at 10.0 s.
    assert rrd.values(lane, "StateChange:state") == ["violated", ""]
    assert rrd.times(lane) == [6_500_000_000, 10_100_000_000]
    errors = list(zip(rrd.times("/errors"), rrd.values("/errors", "TextLog:text"), strict=True))
    assert (
        6_500_000_000,
        "property geofence violated at 6.50 s: stay within 4 m of home; land",
    ) in errors


def test_the_foxglove_layout_shows_properties_beside_behavior_events() -> None:
    from aeroexec.viz.foxglove_layout import foxglove_layout

    panel = foxglove_layout()["configById"]["StateTransitions!behavior-events"]
    values = [path["value"] for path in panel["paths"]]
    assert "/drone1/properties.property" in values
    assert "/drone1/properties.status" in values


def test_the_bus_calls_the_monitor_only_for_what_its_signals_come_from(tmp_path) -> None:
    # `reads`: a session publishes some 25 topics and services (beliefs, process states,
    # the specialist's calls...); signals come from 7, and the others are not delivered.
    from aeroexec.executive.bus import MemoryObserver

    class Seen(PropertyMonitor, MemoryObserver):
        def __init__(self) -> None:
            PropertyMonitor.__init__(self, load_properties(["aeroexec:safety"]))
            MemoryObserver.__init__(self)

        def on_topic(self, record) -> None:
            MemoryObserver.on_topic(self, record)
            PropertyMonitor.on_topic(self, record)

        def on_service_call(self, record) -> None:
            MemoryObserver.on_service_call(self, record)
            PropertyMonitor.on_service_call(self, record)

    seen, everything = Seen(), MemoryObserver()
    with contextlib.redirect_stdout(io.StringIO()):
        simulate(SessionConfig(mission=APPENDIX_C), observers=[seen, everything])
    names = {getattr(r, "topic", None) or r.service for r in seen.records}
    assert names == set(PropertyMonitor.reads)  # all 7, and no other
    # Exactly the records of those 7: none lost on the way, none of the others delivered.
    wanted = [r for r in everything.records if (getattr(r, "topic", None) or r.service) in names]
    assert seen.records == wanted and len(wanted) < len(everything.records)
    assert {getattr(r, "topic", None) or r.service for r in everything.records} > names
