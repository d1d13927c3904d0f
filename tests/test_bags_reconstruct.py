"""Commands reconstructed from active-behavior lists and events (bags hold no service
calls): through whole imports of Aerostack-style bags, and the decision rules one by one.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader
from test_bags_support import NS, START_NS, AerostackBag, short_mission

from aeroexec.bags import import_bag
from aeroexec.bags.extract import ActiveList, Command, Event
from aeroexec.bags.reconstruct import Output, Reconstructor
from aeroexec.executive.messages import EventCode

BEHAVIOR_TOPICS = (
    "mission/command",
    "activate_behavior",
    "inhibit_behavior",
    "behavior_event",
    "list_of_active_behaviors",
)


def derived(path: Path, topics: tuple[str, ...] = BEHAVIOR_TOPICS) -> list[tuple[float, str, Any]]:
    """(seconds from the mission start, topic, payload) of the aeroexec channels, in
    file order."""
    out = []
    with open(path, "rb") as stream:
        for _, channel, message in make_reader(stream).iter_messages(log_time_order=False):
            name = channel.topic.removeprefix("/drone1/")
            if channel.message_encoding == "json" and name in topics:
                t = round((message.log_time - START_NS) / NS, 3)
                out.append((t, name, json.loads(message.data)))
    return out


def summary(items: list[tuple[float, str, Any]]) -> list[tuple[Any, ...]]:
    """One readable tuple per behavior message."""
    rows: list[tuple[Any, ...]] = []
    for t, topic, data in items:
        if topic == "mission/command":
            rows.append(
                (
                    t,
                    data["command"],
                    data["behavior"],
                    data.get("arguments"),
                    data.get("reconstructed", False),
                )
            )
        elif topic in ("activate_behavior", "inhibit_behavior"):
            response = data["response"]
            rows.append(
                (
                    t,
                    "call",
                    topic,
                    data["request"]["behavior"],
                    response.get("uid"),
                    response.get("preempted"),
                )
            )
        elif topic == "behavior_event":
            rows.append(
                (
                    t,
                    "event",
                    data["name"],
                    data["uid"],
                    data["code"],
                    data["detail"],
                    data.get("reconstructed", False),
                )
            )
        else:
            rows.append((t, "list", tuple(data["behaviors"])))
    return rows


SHORT_MISSION = [
    (1.0, "activate_behavior", "TAKE_OFF", {}, True),
    (1.0, "call", "activate_behavior", "TAKE_OFF", 1, []),
    (1.0, "list", ("TAKE_OFF",)),
    (2.0, "activate_behavior", "PAY_ATTENTION", {}, True),
    (2.0, "call", "activate_behavior", "PAY_ATTENTION", 2, []),
    (2.0, "list", ("TAKE_OFF", "PAY_ATTENTION")),
    (3.8, "event", "TAKE_OFF", 1, "GOAL_ACHIEVED", "", False),
    (3.81, "list", ("PAY_ATTENTION",)),
    (5.0, "activate_behavior", "GO_TO_POINT", {"coordinates": [1, 2, 1]}, True),
    (5.0, "call", "activate_behavior", "GO_TO_POINT", 3, []),
    (5.0, "list", ("GO_TO_POINT", "PAY_ATTENTION")),
    (8.6, "event", "GO_TO_POINT", 3, "GOAL_ACHIEVED", "", False),
    (8.61, "list", ("PAY_ATTENTION",)),
    (9.0, "activate_behavior", "KEEP_HOVERING", {}, True),
    (9.0, "call", "activate_behavior", "KEEP_HOVERING", 4, []),
    (9.0, "list", ("PAY_ATTENTION", "KEEP_HOVERING")),
    # gone from the list with no end event: inhibited, and the event aeroexec would send
    (10.0, "inhibit_behavior", "PAY_ATTENTION", None, True),
    (10.0, "call", "inhibit_behavior", "PAY_ATTENTION", None, None),
    (10.0, "event", "PAY_ATTENTION", 2, "INTERRUPTED", "inhibited", True),
    (10.0, "list", ("KEEP_HOVERING",)),
    # LAND appears as KEEP_HOVERING ends INTERRUPTED: a preemption
    (12.5, "activate_behavior", "LAND", {}, True),
    (12.5, "call", "activate_behavior", "LAND", 5, ["KEEP_HOVERING"]),
    (12.5, "list", ("LAND",)),
    (12.5, "event", "KEEP_HOVERING", 4, "INTERRUPTED", "preempted by LAND", False),
    (14.6, "event", "LAND", 5, "GOAL_ACHIEVED", "", False),
    (14.61, "list", ()),
]


def test_short_mission_2018_messages(tmp_path: Path) -> None:
    bag = short_mission().write(tmp_path / "m.bag")
    report = import_bag(bag, tmp_path / "m.mcap")
    assert summary(derived(tmp_path / "m.mcap")) == SHORT_MISSION
    assert report.reconstructed_activations == 5
    assert report.reconstructed_inhibitions == 1
    assert report.notes == ()


def test_june_2017_messages_give_the_same_commands_without_arguments(tmp_path: Path) -> None:
    """listOfBehaviors has no behavior_commands (so no arguments) and behaviorEvent's
    codes carry the literal quotes of the June 2017 constants."""
    bag = short_mission(version="2017").write(tmp_path / "m.bag")
    import_bag(bag, tmp_path / "m.mcap")
    expected = [
        (*row[:3], {}, *row[4:]) if row[1:3] == ("activate_behavior", "GO_TO_POINT") else row
        for row in SHORT_MISSION
    ]
    assert summary(derived(tmp_path / "m.mcap")) == expected


def test_reconstructed_commands_come_first_in_their_instant(tmp_path: Path) -> None:
    """The capability change of an activation follows its command in the file, as the
    executive publishes them (replay attributes changes to the latest command)."""
    bag = short_mission().write(tmp_path / "m.bag")
    import_bag(bag, tmp_path / "m.mcap")
    items = derived(tmp_path / "m.mcap", ("mission/command", "list_of_active_capabilities"))
    at_five = [topic for t, topic, _ in items if t == 5.0]
    assert at_five == ["mission/command", "list_of_active_capabilities"]
    times = []
    at_two = []  # every message of that instant, the bag's own (raw) included
    with open(tmp_path / "m.mcap", "rb") as stream:
        for _, channel, message in make_reader(stream).iter_messages(log_time_order=False):
            times.append(message.log_time)
            if message.log_time == START_NS + 2 * NS:
                at_two.append(channel.topic)
    assert times == sorted(times)  # the whole file is in time order
    # At 2 s the bag's messages wait for the reconstruction horizon (an activation at
    # 1 s is undecided): the reconstructed command and its call still come first.
    assert at_two[:2] == ["/drone1/mission/command", "/drone1/activate_behavior"]
    assert "/ros1/drone1/list_of_active_behaviors" in at_two[2:]


def test_carried_commands_are_not_reconstructed(tmp_path: Path) -> None:
    """A bag with command topics (mapped as activate_command/inhibit_command): those
    commands are kept; the list change they explain adds only the call."""
    bag = AerostackBag()
    commands = "/drone1/behavior_command"
    bag.items.append(
        (
            START_NS + NS,
            commands,
            "droneMsgsROS/msg/BehaviorCommand",
            {"name": "TAKE_OFF", "arguments": ""},
        )
    )
    bag.active(1.1, "TAKE_OFF")
    bag.active(3.0)  # gone without an event, no inhibit command carried: reconstructed
    bag.write(tmp_path / "c.bag")
    mapping = tmp_path / "map.yaml"
    mapping.write_text(
        "topics:\n"
        '  - {topic: "/{drone}/list_of_active_behaviors", kind: active_behaviors}\n'
        '  - {topic: "/{drone}/behavior_command", kind: activate_command}\n'
    )
    report = import_bag(tmp_path / "c.bag", tmp_path / "c.mcap", mapping=mapping)
    assert summary(derived(tmp_path / "c.mcap")) == [
        (1.0, "activate_behavior", "TAKE_OFF", {}, False),
        (1.1, "call", "activate_behavior", "TAKE_OFF", 1, []),
        (1.1, "list", ("TAKE_OFF",)),
        (3.0, "inhibit_behavior", "TAKE_OFF", None, True),
        (3.0, "call", "inhibit_behavior", "TAKE_OFF", None, None),
        (3.0, "event", "TAKE_OFF", 1, "INTERRUPTED", "inhibited", True),
        (3.0, "list", ()),
    ]
    assert report.reconstructed_activations == 0
    assert report.reconstructed_inhibitions == 1
    assert any("no behavior events" in note for note in report.notes)


def test_an_unknown_event_code_is_kept_raw_and_noted(tmp_path: Path) -> None:
    bag = AerostackBag()
    bag.active(1.0, "TAKE_OFF")
    bag.event(2.0, "TAKE_OFF", "BLOCKED")
    bag.active(2.01)
    bag.write(tmp_path / "u.bag")
    report = import_bag(tmp_path / "u.bag", tmp_path / "u.mcap")
    rows = summary(derived(tmp_path / "u.mcap"))
    assert [r for r in rows if r[1] == "event"] == []  # not in the profile's code list
    assert [r for r in rows if r[1] == "inhibit_behavior"] == []  # it did end by itself
    assert any("'BLOCKED'" in note for note in report.notes)


# -- the rules, one by one -------------------------------------------------------------------
def s(seconds: float) -> int:
    return round(seconds * NS)


def run(steps: list[tuple[float, str, Any]], grace_s: float = 0.5) -> list[tuple[Any, ...]]:
    recon = Reconstructor(s(grace_s))
    out: list[Output] = []
    for t, kind, value in steps:
        recon.advance(s(t))
        out.extend(recon.take())
        if kind == "list":
            recon.active_list(s(t), ActiveList(tuple(value), {}))
        elif kind == "event":
            name, code = value
            recon.event(s(t), Event(name, code, str(code), "", None))
        else:
            recon.command(s(t), kind, Command(value, ""))
    recon.finish()
    out.extend(recon.take())
    return summary([(o.time_ns / NS, o.topic, o.data) for o in out])


GOAL = EventCode.GOAL_ACHIEVED
INTERRUPTED = EventCode.INTERRUPTED


def test_an_end_event_just_after_the_drop_means_no_inhibit() -> None:
    rows = run([(1, "list", ["WAIT"]), (2, "list", []), (2.3, "event", ("WAIT", GOAL))])
    assert rows == [
        (1.0, "activate_behavior", "WAIT", {}, True),
        (1.0, "call", "activate_behavior", "WAIT", 1, []),
        (1.0, "list", ("WAIT",)),
        (2.0, "list", ()),
        (2.3, "event", "WAIT", 1, "GOAL_ACHIEVED", "", False),
    ]


def test_a_narrower_grace_turns_the_same_timeline_into_an_inhibit() -> None:
    rows = run([(1, "list", ["WAIT"]), (2, "list", []), (2.3, "event", ("WAIT", GOAL))], 0.1)
    assert (2.0, "inhibit_behavior", "WAIT", None, True) in rows
    events = [r for r in rows if r[1] == "event"]
    assert events == [(2.0, "event", "WAIT", 1, "INTERRUPTED", "inhibited", True)]  # one only


def test_interrupted_with_no_activation_around_it_is_an_inhibit() -> None:
    rows = run([(1, "list", ["WAIT"]), (3, "event", ("WAIT", INTERRUPTED)), (3.01, "list", [])])
    assert rows[3:] == [
        (3.0, "inhibit_behavior", "WAIT", None, True),
        (3.0, "call", "inhibit_behavior", "WAIT", None, None),
        (3.0, "event", "WAIT", 1, "INTERRUPTED", "inhibited", False),  # the bag's own event
        (3.01, "list", ()),
    ]


def test_interrupted_with_an_activation_after_it_is_a_preemption() -> None:
    rows = run(
        [
            (1, "list", ["TAKE_OFF"]),
            (3, "event", ("TAKE_OFF", INTERRUPTED)),
            (3.0, "list", []),
            (3.2, "list", ["LAND"]),
        ]
    )
    assert (3.0, "event", "TAKE_OFF", 1, "INTERRUPTED", "preempted by LAND", False) in rows
    assert (3.2, "call", "activate_behavior", "LAND", 2, ["TAKE_OFF"]) in rows
    assert not [r for r in rows if r[1] == "inhibit_behavior"]


def test_an_event_before_the_list_shows_the_behavior_is_one_activation() -> None:
    rows = run([(1, "event", ("WAIT", GOAL)), (1.1, "list", ["WAIT"]), (1.2, "list", [])])
    assert rows == [
        (1.0, "activate_behavior", "WAIT", {}, True),
        (1.0, "call", "activate_behavior", "WAIT", 1, []),
        (1.0, "event", "WAIT", 1, "GOAL_ACHIEVED", "", False),
        (1.1, "list", ("WAIT",)),
        (1.2, "list", ()),
    ]


def test_events_without_any_list_each_get_an_activation() -> None:
    rows = run([(1, "event", ("WAIT", GOAL)), (5, "event", ("WAIT", GOAL))])
    calls = [r for r in rows if r[1] == "call"]
    assert calls == [
        (1.0, "call", "activate_behavior", "WAIT", 1, []),
        (5.0, "call", "activate_behavior", "WAIT", 2, []),
    ]


def test_an_end_event_long_after_an_inhibit_is_not_a_second_end() -> None:
    recon = Reconstructor(s(0.5))
    for t, kind, value in [(1, "list", ["WAIT"]), (2, "list", []), (3, "event", "WAIT")]:
        recon.advance(s(t))
        if kind == "list":
            recon.active_list(s(t), ActiveList(tuple(value), {}))
        else:
            recon.event(s(t), Event(value, GOAL, "GOAL_ACHIEVED", "", None))
    recon.finish()
    events = [o for o in recon.take() if o.topic == "behavior_event"]
    assert [(e.data["uid"], e.data["code"]) for e in events] == [(1, "INTERRUPTED")]
    assert recon.stats.late_events == 1


def test_a_carried_inhibit_command_explains_the_drop() -> None:
    rows = run(
        [
            (1, "list", ["WAIT"]),
            (2, "inhibit_behavior", "WAIT"),
            (2.1, "list", []),
        ]
    )
    commands = [r for r in rows if r[1] in ("activate_behavior", "inhibit_behavior")]
    assert commands == [
        (1.0, "activate_behavior", "WAIT", {}, True),
        (2.0, "inhibit_behavior", "WAIT", None, False),
    ]
    assert (2.1, "call", "inhibit_behavior", "WAIT", None, None) in rows


def test_the_horizon_holds_back_only_undecided_inputs() -> None:
    recon = Reconstructor(s(0.5))
    assert recon.horizon is None
    recon.active_list(s(1), ActiveList(("WAIT",), {}))
    assert recon.horizon == s(1)
    recon.advance(s(1.9))  # 1 + 2 x grace is not past yet
    assert recon.horizon == s(1) and recon.take() == []
    recon.advance(s(2.1))
    assert recon.horizon is None
    assert [o.topic for o in recon.take()] == [
        "mission/command",
        "activate_behavior",
        "list_of_active_behaviors",
    ]


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("", {}),
        ("coordinates: [1, 2, 3]", {"coordinates": [1, 2, 3]}),
        ("{angle: 90}", {"angle": 90}),
    ],
)
def test_aerostack_argument_text_is_yaml(text: str, expected: dict[str, Any]) -> None:
    from aeroexec.bags.extract import parse_arguments

    assert parse_arguments(text) == expected


def test_argument_text_that_is_not_a_mapping_is_counted() -> None:
    recon = Reconstructor(s(0.5))
    recon.active_list(s(1), ActiveList(("GO_TO_POINT",), {"GO_TO_POINT": "[1, 2"}))
    recon.finish()
    command = recon.take()[0]
    assert command.data["arguments"] == {}
    assert recon.stats.bad_arguments == 1
