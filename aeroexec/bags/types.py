"""Message types for ROS 1 bags: Aerostack's definitions shipped with aeroexec, and each
bag's own definitions from its connection headers.

Shipped definitions live in `aeroexec/data/msg/<folder>/msg/*.msg`; the package name is
the folder name up to `__` (so `droneMsgsROS__2017-06-02_abfdda0` registers as
`droneMsgsROS`: its lower-case 2017 names, `behaviorEvent`, `listOfBehaviors`, ... sit
next to the 2018 `BehaviorEvent`, `ListOfBehaviors`, ...). They are registered over
rosbags' ROS 1 Noetic store (`aerostack_typestore()`).

Decoding a bag connection (`TypeResolver`): the bag's own `message_definition` wins. A
connection with a definition gets a store built from that text alone (cached by text, so
35 connections of one type cost one store, and the stores are kept for the process:
the bags of a fleet repeat the same definitions); only a connection without one falls back to
the shipped store. A bag whose definition disagrees with a shipped one is therefore
decoded as the bag says.

rosbags' `.msg` parser insists on UPPER_CASE constant names and lower_case package names
in field types, which ROS 1 never required: Aerostack's `ProcessState` (`uint8
Created=1`) and `ErrorType` use CamelCase constants (and `AliveSignal` includes
`ProcessState`), and a field typed `droneMsgsROS/BehaviorCommand[]` names a CamelCase
package. `parse_msgdef` accepts both (constants are not serialized; the field layout is
what the definition says).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from importlib import resources

from rosbags.interfaces.typing import Typesdict
from rosbags.typesys import Stores, get_types_from_idl, get_typestore
from rosbags.typesys.base import make_typesdict
from rosbags.typesys.msg import MSGParser
from rosbags.typesys.store import Typestore

#: Where the shipped definitions are, inside the package.
MSG_DIR = ("data", "msg")


class _LenientParser(MSGParser):  # type: ignore[misc]
    """ROS 1 `.msg` grammar with ROS 1's names: constants and packages may be any
    identifier (`uint8 Created=1`, `droneMsgsROS/BehaviorCommand[] commands`)."""

    ConstantName = MSGParser.MixedSnake
    PackageName = MSGParser.MixedSnake


def ros2_name(type_name: str) -> str:
    """The name a type is registered and decoded under: `droneMsgsROS/BehaviorEvent` ->
    `droneMsgsROS/msg/BehaviorEvent` (rosbags' names); a ROS 2 service or action type
    (`example_interfaces/srv/AddTwoInts_Event`) under `/msg/` too, where rosbags'
    definition generator wants every type."""
    package = type_name.split("/", 1)[0]
    name = type_name.rsplit("/", 1)[-1]
    return f"{package}/msg/{name}"


def ros1_name(msgtype: str) -> str:
    """`droneMsgsROS/msg/BehaviorEvent` -> `droneMsgsROS/BehaviorEvent` (the bag's names)."""
    return msgtype.replace("/msg/", "/", 1)


def parse_msgdef(text: str, msgtype: str) -> dict[str, object]:
    """Parse a ROS 1 definition (with its `MSG:` sub-definitions) into rosbags' typesdict.

    Raises rosbags' `TypesysError` when the text is not a message definition."""
    return make_typesdict(_LenientParser(f"MSG: {ros2_name(msgtype)}\n{text}").specification())  # type: ignore[no-any-return]


def idl_types(text: str) -> Typesdict:
    """The types of a `ros2idl` definition: one IDL text, or several, each after a
    `====...` line and an `IDL: pkg/msg/Name` line (rosbag2's MCAP writer)."""
    separator = "=" * 80 + "\n"
    if not text.startswith(f"{separator}IDL: "):
        return get_types_from_idl(text)
    types: Typesdict = {}
    for part in text.split(separator)[1:]:
        _, idl = part.split("\n", 1)
        types.update(get_types_from_idl(idl))
    return types


def shipped_definitions() -> dict[str, str]:
    """Type name (`droneMsgsROS/msg/BehaviorEvent`) -> `.msg` text, of every shipped file."""
    root = resources.files("aeroexec").joinpath(*MSG_DIR)
    found: dict[str, str] = {}
    for folder in sorted(root.iterdir(), key=lambda p: p.name):
        msg_dir = folder.joinpath("msg")
        if not folder.is_dir() or not msg_dir.is_dir():
            continue
        package = folder.name.split("__", 1)[0]
        for item in sorted(msg_dir.iterdir(), key=lambda p: p.name):
            if item.name.endswith(".msg"):
                found[f"{package}/msg/{item.name[:-4]}"] = item.read_text(encoding="utf-8")
    return found


def aerostack_typestore() -> Typestore:
    """A new store: ROS 1 Noetic's types plus every shipped Aerostack definition.

    Writers (tests, tools) use it to produce Aerostack bags with the real definitions:
    `Writer.add_connection(topic, "droneMsgsROS/msg/BehaviorEvent", typestore=store)`."""
    store = get_typestore(Stores.ROS1_NOETIC)
    types: dict[str, object] = {}
    for name, text in shipped_definitions().items():
        types.update(parse_msgdef(text, name))
    store.register(types)  # type: ignore[arg-type]
    return store


@functools.lru_cache(maxsize=1)
def _shipped_store() -> Typestore:
    return aerostack_typestore()


@dataclass(frozen=True, slots=True)
class Decoder:
    """How to decode one connection: a store that knows its type, and where the
    definition came from (`bag` or `shipped`)."""

    store: Typestore
    msgtype: str
    origin: str
    #: Why the definition is doubtful ("" when it matches the bag's md5sum or is the bag's).
    warning: str = ""

    #: ROS 2 (CDR) rather than ROS 1 serialization.
    cdr: bool = False

    def decode(self, data: bytes | memoryview) -> object:
        if self.cdr:
            return self.store.deserialize_cdr(data, self.msgtype)
        return self.store.deserialize_ros1(data, self.msgtype)


class TypeResolver:
    """Finds a `Decoder` for bag connections (see the module docstring)."""

    def __init__(self) -> None:
        self._by_text: dict[tuple[str, str], Typestore] = {}

    def decoder(
        self, msgtype: str, msgdef: str, md5sum: str, schema_encoding: str = "ros1msg"
    ) -> Decoder:
        """A decoder for a connection of `msgtype` (rosbags' `pkg/msg/Name`). Raises
        `ValueError` with the reason when the type cannot be decoded. A ROS 2 connection
        (`ros2msg`, `ros2idl`) always carries its definition by then (the bag's, or the
        one aeroexec completed: see `Ros2Types`)."""
        if schema_encoding in ("ros2msg", "ros2idl"):
            if not msgdef.strip():
                raise ValueError(
                    f"{msgtype}: the bag has no definition for it and aeroexec knows none"
                )
            name = ros2_name(msgtype)
            store = _store_from_text(name, msgdef, schema_encoding)
            return Decoder(store, name, "bag", cdr=True)
        if msgdef.strip():
            return Decoder(self._from_text(msgtype, msgdef), msgtype, "bag")
        store = _shipped_store()
        if msgtype not in store.fielddefs:
            raise ValueError(
                f"{ros1_name(msgtype)}: the bag has no definition for it and aeroexec ships none"
            )
        try:
            _, shipped_md5 = store.generate_msgdef(msgtype)
        except Exception as exc:  # rosbags raises several kinds here
            raise ValueError(f"{ros1_name(msgtype)}: {exc}") from None
        warning = ""
        if md5sum and md5sum != "*" and shipped_md5 != md5sum:
            warning = (
                f"{ros1_name(msgtype)}: the bag has no definition and its md5sum {md5sum} "
                f"differs from aeroexec's shipped one ({shipped_md5})"
            )
        return Decoder(store, msgtype, "shipped", warning)

    def _from_text(self, msgtype: str, msgdef: str) -> Typestore:
        key = (msgtype, msgdef)
        store = self._by_text.get(key)
        if store is None:
            store = self._by_text[key] = _store_from_text(msgtype, msgdef)
        return store


@functools.lru_cache(maxsize=256)
def _store_from_text(msgtype: str, msgdef: str, encoding: str = "ros1msg") -> Typestore:
    """A store that decodes `msgtype` as `msgdef` defines it. Kept for the process:
    building the (de)serializers is rosbags' code generation (~5 ms a type, more than
    reading a small bag), and a fleet of bags repeats the same definitions. Keyed by the
    definition text, so a bag that defines a type differently gets its own store; the
    store is only read (`deserialize_ros1`) once built. A definition that cannot be used
    raises each time (lru_cache keeps no exceptions)."""
    store = get_typestore(Stores.EMPTY)
    try:
        if encoding == "ros2idl":
            store.register(idl_types(msgdef))
        else:
            store.register(parse_msgdef(msgdef, msgtype))  # type: ignore[arg-type]
        store.get_msgdef(msgtype)  # generate the (de)serializers now: fail here
    except Exception as exc:  # TypesysError, KeyError for a missing sub-type...
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ValueError(
            f"{ros1_name(msgtype)}: the bag's definition cannot be used: {first}"
        ) from None
    return store
