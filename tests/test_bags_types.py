"""Message types: the shipped Aerostack definitions, and the bag's own definition first."""

from __future__ import annotations

from pathlib import Path

import pytest
from rosbags.rosbag1 import Reader, Writer
from rosbags.typesys import Stores, get_typestore
from test_bags_support import AEROSTACK_BAG, NS, START_NS, AerostackBag

from aeroexec.bags import aerostack_typestore, import_bag
from aeroexec.bags.types import TypeResolver, parse_msgdef, shipped_definitions
from aeroexec.recording import open_recording

#: droneMsgsROS/behaviorEvent as of Ahrovan/dronemsgsros @ 1826e34 (2017-03-10): integer
#: codes. aeroexec does not ship it (its name clashes with June 2017's string version).
BEHAVIOR_EVENT_2017_03 = """# behavior name
string name

#behavior mode
string mode

# event type
int32 event

# event type definitions
int32 ACHIEVED\t\t= 1
int32 TIME_OUT\t\t= 2
int32 WRONG_PROGRESS\t= 3
int32 BLOCKED\t\t= 4"""


def test_every_shipped_definition_is_registered() -> None:
    shipped = shipped_definitions()
    assert len(shipped) == 21
    store = aerostack_typestore()
    for name in shipped:
        assert name in store.fielddefs, name
    # June 2017 names sit next to the 2018 ones in one droneMsgsROS package
    assert "droneMsgsROS/msg/behaviorEvent" in shipped
    assert "droneMsgsROS/msg/BehaviorEvent" in shipped
    fields = [f for f, _ in store.fielddefs["droneMsgsROS/msg/listOfBehaviors"][1]]
    assert fields == ["active_behaviors"]


def test_shipped_definitions_hash_like_the_real_aerostack_bag() -> None:
    """The md5sums rosbags computes from the shipped files equal those a real 2017
    Aerostack system wrote into its bag, CamelCase constants (ProcessState) included."""
    store = aerostack_typestore()
    with Reader(AEROSTACK_BAG) as reader:
        digests = {c.msgtype: c.digest for c in reader.connections}
    for msgtype in ("droneMsgsROS/msg/AliveSignal", "droneMsgsROS/msg/ProcessDescriptorList"):
        assert store.generate_msgdef(msgtype)[1] == digests[msgtype]


def test_camelcase_constants_and_packages_parse() -> None:
    """rosbags' own parser refuses both; ROS 1 allowed them and Aerostack used them."""
    from rosbags.typesys import TypesysError, get_types_from_msg

    text = "uint8 state\nuint8 Created=1\ndroneMsgsROS/BehaviorCommand[] commands\n"
    with pytest.raises(TypesysError):
        get_types_from_msg(text, "x/msg/Y")
    types = parse_msgdef(text, "x/Y")
    constants, fields = types["x/msg/Y"]
    assert [c[0] for c in constants] == ["Created"]
    assert [f[0] for f in fields] == ["state", "commands"]


def _write_with(path: Path, msgtype: str, msgdef: str, md5sum: str, values: list[object]) -> None:
    store = get_typestore(Stores.EMPTY)
    store.register(parse_msgdef(msgdef, msgtype) if msgdef else {})  # type: ignore[arg-type]
    with Writer(path) as writer:
        connection = writer.add_connection(
            "/drone1/behavior_event", msgtype, msgdef=msgdef, md5sum=md5sum
        )
        for i, message in enumerate(values):
            writer.write(connection, START_NS + (i + 1) * NS, bytes(message))  # type: ignore[arg-type]


def test_the_bags_own_definition_wins_over_the_shipped_one(tmp_path: Path) -> None:
    """A March 2017 bag: same type name as June 2017's behaviorEvent, other layout."""
    msgtype = "droneMsgsROS/msg/behaviorEvent"
    store = get_typestore(Stores.EMPTY)
    store.register(parse_msgdef(BEHAVIOR_EVENT_2017_03, msgtype))  # type: ignore[arg-type]
    _, md5 = store.generate_msgdef(msgtype)
    cls = store.types[msgtype]
    events = [
        store.serialize_ros1(cls(name="TAKE_OFF", mode="", event=1), msgtype),  # type: ignore[call-arg]
        store.serialize_ros1(cls(name="LAND", mode="", event=2), msgtype),  # type: ignore[call-arg]
    ]
    bag = tmp_path / "march.bag"
    _write_with(bag, msgtype, BEHAVIOR_EVENT_2017_03, md5, events)
    import_bag(bag, tmp_path / "march.mcap")
    found = [
        (r.data["name"], r.data["code"])  # type: ignore[union-attr]
        for r in open_recording(tmp_path / "march.mcap").records()
        if r.topic == "/drone1/behavior_event"
    ]
    assert found == [("TAKE_OFF", "GOAL_ACHIEVED"), ("LAND", "TIME_OUT")]


def test_a_connection_without_definition_falls_back_to_the_shipped_one(tmp_path: Path) -> None:
    msgtype = "droneMsgsROS/msg/BehaviorEvent"
    store = aerostack_typestore()
    _, md5 = store.generate_msgdef(msgtype)
    source = AerostackBag()
    source.event(1.0, "TAKE_OFF", "GOAL_ACHIEVED")
    source.write(tmp_path / "full.bag")
    with Reader(tmp_path / "full.bag") as reader:
        data = [bytes(d) for _, _, d in reader.messages()]
    bag = tmp_path / "bare.bag"
    _write_with(bag, msgtype, "", md5, data)
    with Reader(bag) as reader:
        assert reader.connections[0].msgdef.data == ""
    report = import_bag(bag, tmp_path / "bare.mcap")
    assert report.mapped == {"behavior_event": "/drone1/behavior_event"}
    assert report.derived["behavior_event"] == 1
    assert not any("md5sum" in n for n in report.notes)
    # the same bytes under a wrong md5sum: still decoded, with a warning
    wrong = tmp_path / "wrong.bag"
    _write_with(wrong, msgtype, "", "0" * 32, data)
    report = import_bag(wrong, tmp_path / "wrong.mcap")
    assert report.derived["behavior_event"] == 1
    assert any("differs from aeroexec's shipped one" in n for n in report.notes)


def test_a_type_nobody_defines_is_carried_over_raw_only(tmp_path: Path) -> None:
    bag = tmp_path / "unknown.bag"
    with Writer(bag) as writer:
        connection = writer.add_connection(
            "/drone1/behavior_event", "acme_msgs/msg/Event", msgdef="", md5sum="1" * 32
        )
        writer.write(connection, START_NS, b"\x00\x01")
    report = import_bag(bag, tmp_path / "unknown.mcap")
    assert report.messages == 1 and report.mapped == {}
    assert report.notes == (
        "/drone1/behavior_event not mapped as behavior_event: acme_msgs/Event: the bag has "
        "no definition for it and aeroexec ships none",
    )


def test_resolver_builds_one_store_per_distinct_definition() -> None:
    resolver = TypeResolver()
    with Reader(AEROSTACK_BAG) as reader:
        alive = [c for c in reader.connections if c.topic == "/drone1/process_alive_signal"]
    decoders = {id(resolver.decoder(c.msgtype, c.msgdef.data, c.digest).store) for c in alive}
    assert len(alive) > 30 and len(decoders) == 1


def test_stores_are_kept_for_the_process_by_definition_text() -> None:
    """A second import (a fleet of bags) reuses the stores the first one built; a
    different definition of the same type still gets its own store."""
    msgtype = "aeroexec_test/msg/Kept"
    first = TypeResolver().decoder(msgtype, "int32 a", "")
    again = TypeResolver().decoder(msgtype, "int32 a", "")
    other = TypeResolver().decoder(msgtype, "int32 a\nstring b", "")
    assert again.store is first.store
    assert other.store is not first.store
    assert first.decode(b"\x07\x00\x00\x00").a == 7  # type: ignore[attr-defined]
    decoded = other.decode(b"\x07\x00\x00\x00\x02\x00\x00\x00hi")
    assert (decoded.a, decoded.b) == (7, "hi")  # type: ignore[attr-defined]
    for _ in range(2):  # a failure is not kept as a store: it fails again
        with pytest.raises(ValueError, match="definition cannot be used"):
            TypeResolver().decoder(msgtype, "int32 a\nNoSuchPackage/Missing c", "")
