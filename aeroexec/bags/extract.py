"""Plain values out of decoded ROS messages, by field names rather than by type names.

Aerostack renamed its messages several times (`behaviorEvent` -> `BehaviorEvent`,
`listOfBehaviors.active_behaviors` -> `ListOfBehaviors.behaviors`, integer event codes
-> strings) and a pose may come as `droneMsgsROS/dronePose`, `geometry_msgs/PoseStamped`,
`nav_msgs/Odometry`... Each function here looks for the fields it knows and returns None
when the message has none of them, so one mapping handles every version.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import yaml

from aeroexec.executive.messages import EventCode

#: 2017-03 `behaviorEvent.event` (int32): ACHIEVED=1, TIME_OUT=2, WRONG_PROGRESS=3,
#: BLOCKED=4 (BLOCKED has no 2017-06 equivalent: such events are counted, not mapped).
_INT_CODES_2017_03 = {
    1: EventCode.GOAL_ACHIEVED,
    2: EventCode.TIME_OUT,
    3: EventCode.WRONG_PROGRESS,
}
#: 2019+ `BehaviorActivationFinished.termination_cause` (int8); SITUATION_CHANGE=4 has no
#: 2017 equivalent.
_TERMINATION_CAUSES = {
    1: EventCode.GOAL_ACHIEVED,
    2: EventCode.TIME_OUT,
    3: EventCode.WRONG_PROGRESS,
    5: EventCode.PROCESS_FAILURE,
    6: EventCode.INTERRUPTED,
}
#: droneMsgsROS/droneStatus values that mean "in the air".
_FLYING_STATUSES = frozenset({3, 4, 6, 8, 9})  # FLYING, HOVERING, TAKING_OFF, LANDING, LOOPING
#: as2_msgs/PlatformStatus states in the air: TAKING_OFF=2, FLYING=3, LANDING=4.
_AS2_FLYING_STATES = frozenset({2, 3, 4})
#: droneMsgsROS/ProcessState values of a running process (Running=3, Started=7).
_RUNNING_STATES = frozenset({3, 7})


@dataclass(frozen=True, slots=True)
class Event:
    name: str
    #: The aeroexec code, or None when the message's code has no aeroexec equivalent.
    code: EventCode | None
    #: The code as the bag has it (for notes).
    raw_code: str
    detail: str
    bag_uid: float | None


@dataclass(frozen=True, slots=True)
class ActiveList:
    names: tuple[str, ...]
    #: Behavior -> its argument text, when the message carries behavior commands (2018).
    arguments: dict[str, str]


@dataclass(frozen=True, slots=True)
class Command:
    name: str
    arguments: str


@dataclass(frozen=True, slots=True)
class Pose:
    position: tuple[float, float, float]
    yaw: float


def _field(message: object, *names: str) -> Any:
    for name in names:
        if hasattr(message, name):
            return getattr(message, name)
    return None


def _str(value: object) -> str:
    return value if isinstance(value, str) else ""


def _code_text(text: str) -> str:
    """Until 2017-06-22 the constants were written `= "GOAL_ACHIEVED"` and ROS kept the
    quotes in the value: strip them."""
    return text.strip().strip("\"'").strip()


def event(message: object) -> Event | None:
    name = _field(message, "name")
    if not isinstance(name, str):
        return None
    code: EventCode | None = None
    text = _field(message, "behavior_event_code")
    if isinstance(text, str):
        raw = _code_text(text)
        try:
            code = EventCode(raw.upper())
        except ValueError:
            code = None
    else:
        number = _field(message, "event", "termination_cause")
        if isinstance(number, bool) or not isinstance(number, int):
            return None
        raw = str(number)
        table = _INT_CODES_2017_03 if hasattr(message, "event") else _TERMINATION_CAUSES
        code = table.get(number)
    details = [
        _str(_field(message, key)).strip()
        for key in ("failed_belief", "belief_conflict", "error_message")
    ]
    uid = _field(message, "uid")
    bag_uid = float(uid) if isinstance(uid, (int, float)) and not isinstance(uid, bool) else None
    return Event(name, code, raw, "; ".join(d for d in details if d), bag_uid)


def active_list(message: object) -> ActiveList | None:
    names = _field(message, "behaviors", "active_behaviors")
    if not isinstance(names, (list, tuple)):
        return None
    arguments: dict[str, str] = {}
    for command in _field(message, "behavior_commands") or ():
        name = _field(command, "name")
        if isinstance(name, str):
            arguments[name] = _str(_field(command, "arguments"))
    ordered = tuple(dict.fromkeys(str(n) for n in names))
    return ActiveList(ordered, arguments)


def capabilities(message: object) -> tuple[str, ...] | None:
    items = _field(message, "capabilities", "active_capabilities")
    if not isinstance(items, (list, tuple)):
        return None
    names = [item if isinstance(item, str) else _str(_field(item, "name")) for item in items]
    return tuple(dict.fromkeys(n for n in names if n))


def beliefs(message: object) -> tuple[str, ...] | None:
    """A snapshot: AllBeliefs' newline-separated text, or a list of beliefs."""
    value = _field(message, "beliefs")
    if isinstance(value, str):
        lines: Sequence[str] = value.splitlines()
    elif isinstance(value, (list, tuple)):
        lines = [str(v) for v in value]
    else:
        return None
    return tuple(dict.fromkeys(line.strip() for line in lines if line.strip()))


def process(message: object, drone: str) -> tuple[str, bool] | None:
    """(process name without the drone namespace, running) of an AliveSignal."""
    name = _field(message, "process_name")
    state = _field(message, "current_state")
    value = _field(state, "state") if state is not None else None
    if not isinstance(name, str) or isinstance(value, bool) or not isinstance(value, int):
        return None
    prefix = f"/{drone}/"
    short = name[len(prefix) :] if name.startswith(prefix) else name.lstrip("/")
    return short, value in _RUNNING_STATES


def command(message: object) -> Command | None:
    name = _field(message, "name", "behavior")
    if not isinstance(name, str) or not name:
        return None
    return Command(name, _str(_field(message, "arguments")))


def parse_arguments(text: str) -> dict[str, Any] | None:
    """Aerostack's argument text (YAML, `coordinates: [1, 2, 3]`) as a dict; {} when
    empty, None when it is not a YAML mapping."""
    if not text.strip():
        return {}
    try:
        value = yaml.safe_load(text)
    except yaml.YAMLError:
        return None
    if value is None:
        return {}
    if not isinstance(value, dict):
        return None
    return {str(k): v for k, v in value.items()}


def _float(value: object) -> float | None:
    if type(value) is float:
        return value
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    return None


def _floats(*values: object) -> tuple[float, ...] | None:
    out = []
    for value in values:
        number = _float(value)
        if number is None:
            return None
        out.append(number)
    return tuple(out)


def _yaw(orientation: object) -> float | None:
    x = _float(getattr(orientation, "x", None))
    y = _float(getattr(orientation, "y", None))
    z = _float(getattr(orientation, "z", None))
    w = _float(getattr(orientation, "w", None))
    if x is None or y is None or z is None or w is None:
        return None
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def pose(message: object) -> Pose | None:
    """Position and yaw from a dronePose (x, y, z, yaw), a Pose/PoseStamped/
    PoseWithCovariance[Stamped]/Odometry (position + orientation quaternion), or a
    turtlesim-like (x, y, theta) message."""
    for _ in range(4):  # PoseStamped.pose, Odometry.pose.pose: unwrap a few levels
        inner = getattr(message, "pose", None)
        if inner is None:
            break
        message = inner
    position = getattr(message, "position", None)
    if position is not None:
        x = _float(getattr(position, "x", None))
        y = _float(getattr(position, "y", None))
        z = _float(getattr(position, "z", None))
        yaw = _yaw(getattr(message, "orientation", None))
        if x is None or y is None or z is None or yaw is None:
            return None
        return Pose((x, y, z), yaw)
    x = _float(getattr(message, "x", None))
    y = _float(getattr(message, "y", None))
    z = _float(getattr(message, "z", 0.0))
    heading = _float(_field(message, "yaw", "theta"))
    if x is None or y is None or z is None or heading is None:
        return None
    return Pose((x, y, z), heading)


def velocity(message: object) -> tuple[float, float, float] | None:
    """Linear velocity from a droneSpeeds (dx, dy, dz), a Twist/TwistStamped/
    TwistWithCovariance[Stamped] or an Odometry."""
    for _ in range(4):
        inner = getattr(message, "twist", None)
        if inner is None:
            break
        message = inner
    linear = getattr(message, "linear", None)
    if linear is not None:
        values = _floats(*(getattr(linear, a, None) for a in "xyz"))
    else:
        values = _floats(*(getattr(message, a, None) for a in ("dx", "dy", "dz")))
    if values is None:
        return None
    return (values[0], values[1], values[2])


def battery(message: object) -> float | None:
    """Charge as a fraction 0..1: droneMsgsROS/battery's batteryPercent (0..100) or
    sensor_msgs/BatteryState's percentage (0..1)."""
    percent = _floats(getattr(message, "batteryPercent", None))
    if percent is not None:
        value = percent[0] / 100.0
    else:
        fraction = _floats(getattr(message, "percentage", None))
        if fraction is None:
            return None
        value = fraction[0]
    if not math.isfinite(value):
        return None
    return min(max(value, 0.0), 1.0)


def flying(message: object) -> bool | None:
    """In the air? From droneMsgsROS/droneStatus (`status`), Aerostack2's
    as2_msgs/PlatformInfo (`status.state`: TAKING_OFF, FLYING, LANDING) or a `flying`
    flag."""
    flag = getattr(message, "flying", None)
    if isinstance(flag, bool):
        return flag
    status = getattr(message, "status", None)
    state = getattr(status, "state", None)
    if isinstance(state, int) and not isinstance(state, bool):
        return state in _AS2_FLYING_STATES
    if isinstance(status, bool) or not isinstance(status, int):
        return None
    return status in _FLYING_STATUSES


def armed(message: object) -> bool | None:
    """Armed? From a flight status with an `armed` flag (Aerostack2's PlatformInfo);
    None when it has none."""
    flag = getattr(message, "armed", None)
    return flag if isinstance(flag, bool) else None


def plain(value: object) -> Any:
    """A decoded message as JSON-ready values: messages as dicts (by field), arrays
    (numpy) as lists, numbers and strings as they are."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {
            f.name: plain(getattr(value, f.name))
            for f in dataclasses.fields(value)
            # rosbags' __msgtype__, and the constants (UPPER_CASE in ROS 2), which its
            # generated classes list as fields too
            if not f.name.startswith("__") and not f.name.isupper()
        }
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    tolist = getattr(value, "tolist", None)  # numpy arrays and scalars
    if callable(tolist):
        return plain(tolist())
    if isinstance(value, bytes):
        return list(value)
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    return value
