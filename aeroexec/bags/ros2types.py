"""Message types for ROS 2 bags: what a bag does not define, completed.

A rosbag2 bag (Humble and later) carries each topic's definition (`ros2msg`, or
`ros2idl`); `types.TypeResolver` decodes with the bag's own text. Two cases need more:

* **Service events** (Iron and later record service calls on `<service>/_service_event`
  topics): rosbag2 stores the raw `.srv` text (request `---` response) as the
  definition of `<pkg>/srv/<Name>_Event` (MCAP), or nothing at all (sqlite3: the text
  sits in `message_definitions` under `<pkg>/srv/<Name>`). No reader decodes that
  (ros2/rosbag2#2365): `service_event_definition` splits the text at `---`, builds
  `<Name>_Request` and `<Name>_Response` and the real event type around them
  (`service_msgs/ServiceEventInfo info`, `<Name>_Request[<=1] request`,
  `<Name>_Response[<=1] response`), and writes the full concatenated `ros2msg`
  definition Foxglove expects.
* **Bags without definitions** (rosbag2 before Iron, or a type the bag left out): the
  definition comes from the `Ros2Types` store: rosbags' Jazzy types, the interfaces
  aeroexec ships (`aeroexec/data/msg_ros2/`: Aerostack2's `as2_msgs`, `std_srvs`) and the
  `.msg`/`.srv`/`.action` folders given with `--types DIR`.

Every type is registered under `<pkg>/msg/<Name>` (`types.ros2_name`): rosbags'
definition generator only writes such names, and the layout is what matters to CDR.
"""

from __future__ import annotations

import functools
import os
from importlib import resources
from pathlib import Path

from rosbags.interfaces.typing import Typesdict
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.store import Typestore

from aeroexec.bags.types import parse_msgdef, ros2_name
from aeroexec.errors import Mark, RecordingError

#: The ROS 2 interfaces aeroexec ships, inside the package: `<pkg>/{msg,srv,action}/`.
MSG2_DIR = ("data", "msg_ros2")
_KINDS = {".msg": "msg", ".srv": "srv", ".action": "action"}
#: The fields rosidl puts around a service's request and response in its event type.
SERVICE_EVENT_INFO = "service_msgs/ServiceEventInfo info"


def split_sections(text: str) -> list[str]:
    """A `.srv` or `.action` text split at its `---` lines."""
    sections: list[list[str]] = [[]]
    for line in text.splitlines():
        if line.strip() == "---":
            sections.append([])
        else:
            sections[-1].append(line)
    return ["\n".join(lines) + "\n" for lines in sections]


def is_interface_text(text: str) -> bool:
    """Is this a `.srv`/`.action` text (a `---` line before any `MSG:` section)?"""
    head = text.split("\n" + "=" * 80, 1)[0]
    return any(line.strip() == "---" for line in head.splitlines())


def _msg(pkg: str, name: str, text: str) -> Typesdict:
    return parse_msgdef(text, f"{pkg}/msg/{name}")  # type: ignore[return-value]


def _event(pkg: str, name: str) -> str:
    return (
        f"{SERVICE_EVENT_INFO}\n{pkg}/{name}_Request[<=1] request\n"
        f"{pkg}/{name}_Response[<=1] response\n"
    )


def service_types(pkg: str, name: str, request: str, response: str) -> Typesdict:
    """`<Name>_Request`, `<Name>_Response` and `<Name>_Event` of one service."""
    types: Typesdict = {}
    types.update(_msg(pkg, f"{name}_Request", request))
    types.update(_msg(pkg, f"{name}_Response", response))
    types.update(_msg(pkg, f"{name}_Event", _event(pkg, name)))
    return types


def interface_types(kind: str, pkg: str, name: str, text: str) -> Typesdict:
    """The types rosidl generates from one `.msg`, `.srv` or `.action` file. Raises
    `ValueError` when the text has the wrong number of `---` sections."""
    if kind == "msg":
        return _msg(pkg, name, text)
    sections = split_sections(text)
    if kind == "srv":
        if len(sections) != 2:
            raise ValueError(f"a .srv has one '---' line, {pkg}/{name} has {len(sections) - 1}")
        return service_types(pkg, name, *sections)
    if len(sections) != 3:
        raise ValueError(f"an .action has two '---' lines, {pkg}/{name} has {len(sections) - 1}")
    goal, result, feedback = sections
    uuid = "unique_identifier_msgs/UUID goal_id\n"
    types: Typesdict = {}
    types.update(_msg(pkg, f"{name}_Goal", goal))
    types.update(_msg(pkg, f"{name}_Result", result))
    types.update(_msg(pkg, f"{name}_Feedback", feedback))
    types.update(_msg(pkg, f"{name}_FeedbackMessage", f"{uuid}{pkg}/{name}_Feedback feedback\n"))
    types.update(
        service_types(
            pkg,
            f"{name}_SendGoal",
            f"{uuid}{pkg}/{name}_Goal goal\n",
            "bool accepted\nbuiltin_interfaces/Time stamp\n",
        )
    )
    types.update(
        service_types(pkg, f"{name}_GetResult", uuid, f"int8 status\n{pkg}/{name}_Result result\n")
    )
    return types


def read_interfaces(root: Path | object) -> dict[tuple[str, str, str], str]:
    """(kind, package, name) -> text of every `<pkg>/{msg,srv,action}/*` under `root`
    (a folder of packages, or one package folder)."""
    found: dict[tuple[str, str, str], str] = {}
    folders = [root] if _is_package(root) else sorted(_children(root), key=_name)
    for package in folders:
        if not _is_package(package):
            continue
        for kind_dir in sorted(_children(package), key=_name):
            for item in sorted(_children(kind_dir), key=_name):
                suffix = Path(_name(item)).suffix
                if _KINDS.get(suffix) == _name(kind_dir):
                    key = (_KINDS[suffix], _name(package), Path(_name(item)).stem)
                    found[key] = item.read_text(encoding="utf-8")  # type: ignore[attr-defined]
    return found


def _name(item: object) -> str:
    return str(item.name)  # type: ignore[attr-defined]


def _children(item: object) -> list[object]:
    return list(item.iterdir()) if item.is_dir() else []  # type: ignore[attr-defined]


def _is_package(item: object) -> bool:
    return any(_name(c) in ("msg", "srv", "action") for c in _children(item))


@functools.lru_cache(maxsize=1)
def _shipped_types() -> Typesdict:
    """The shipped interfaces, parsed once per process (~60 files: 0.1 s)."""
    return _parse(read_interfaces(resources.files("aeroexec").joinpath(*MSG2_DIR)), None)


def _parse(found: dict[tuple[str, str, str], str], where: str | None) -> Typesdict:
    types: Typesdict = {}
    for (kind, pkg, name), text in found.items():
        try:
            types.update(interface_types(kind, pkg, name, text))
        except Exception as exc:  # TypesysError, ValueError: name the file
            if where is None:
                raise
            raise RecordingError(
                f"cannot read the definition: {_first_line(exc)}",
                Mark(str(Path(where) / pkg / kind / f"{name}.{kind}")),
            ) from None
    return types


class Ros2Types:
    """The fallback store of a ROS 2 import: Jazzy + shipped interfaces + `--types`.
    `--types` is read and checked at once; the store is built when first needed (a bag
    with every definition and no service events never needs it: building it is rosbags'
    code generation for some 400 types)."""

    def __init__(self, types_dir: str | os.PathLike[str] | None = None) -> None:
        self._store: Typestore | None = None
        self._user: Typesdict = {}
        self.types_dir = None if types_dir is None else str(types_dir)
        if types_dir is not None:
            folder = Path(types_dir)
            if not folder.is_dir():
                raise RecordingError(
                    "--types wants a folder of .msg/.srv/.action files", Mark(str(types_dir))
                )
            found = read_interfaces(folder)
            if not found:
                raise RecordingError(
                    "no <package>/msg, srv or action folders with definitions in it",
                    Mark(str(types_dir)),
                )
            self._user = _parse(found, str(types_dir))

    @property
    def store(self) -> Typestore:
        if self._store is None:
            store = get_typestore(Stores.ROS2_JAZZY)
            # --types wins over the shipped definitions, and both over Jazzy's
            types = {**_shipped_types(), **self._user}
            for name in types:
                store.fielddefs.pop(name, None)
            store.register(types)
            self._store = store
        return self._store

    def origin(self, msgtype: str) -> str:
        """Where the definition of `msgtype` came from: the `--types` folder, or
        `aeroexec` (shipped, or rosbags' Jazzy types)."""
        if self.types_dir is not None and ros2_name(msgtype) in self._user:
            return self.types_dir
        return "aeroexec"

    def definition(self, msgtype: str) -> str | None:
        """The full `ros2msg` definition (with its `MSG:` sections) of `msgtype`, or None
        when no definition of it (or of a type it uses) is known."""
        try:
            return self.store.generate_msgdef(ros2_name(msgtype), ros_version=2)[0]  # type: ignore[no-any-return]
        except Exception:  # TypesysError for an unknown (sub-)type
            return None

    def service_event_definition(self, msgtype: str, srv_text: str) -> str:
        """The real definition of `<pkg>/srv/<Name>_Event` from its `.srv` text, or of an
        action's `<pkg>/action/<Name>_SendGoal_Event` / `_GetResult_Event` from its
        `.action` text (see the module docstring). Raises `ValueError` with the reason."""
        pkg = msgtype.split("/", 1)[0]
        name = msgtype.rsplit("/", 1)[-1]
        if not name.endswith("_Event"):
            raise ValueError(f"{msgtype} is not a service event type")
        sections = split_sections(srv_text.split("\n" + "=" * 80, 1)[0])
        service = name[: -len("_Event")]
        action = service.rsplit("_", 1)[0]
        if len(sections) == 3 and service.endswith(("_SendGoal", "_GetResult")):
            make = lambda: interface_types("action", pkg, action, srv_text)  # noqa: E731
        elif len(sections) == 2:
            make = lambda: service_types(pkg, service, *sections)  # noqa: E731
        else:
            raise ValueError(f"{msgtype}: the service text has {len(sections) - 1} '---' lines")
        try:
            types = make()
            for type_name in types:
                self.store.fielddefs.pop(type_name, None)
            self.store.register(types)
        except Exception as exc:
            raise ValueError(f"{msgtype}: {_first_line(exc)}") from None
        text = self.definition(msgtype)
        if text is None:
            raise ValueError(f"{msgtype}: a type its request or response uses is unknown")
        return text


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__
