"""Messages for Foxglove's and Lichtblick's own panels, derived from what the executive
records: the 3D panel's frame tree and scene, and a call log for the Log panel.
`PanelFeed` derives them as a session's messages come, and hands each to a callback: the
recorder writes them, and a live publisher can send the very same ones.

* `vehicle/transform` (`foxglove.FrameTransform`): `world` -> `<drone>/base_link`, with
  each `vehicle/state` whose pose changed: the vehicle's position and yaw as the 3D
  panel's frame tree; and at the session's first log time when its start pose is known.
* The scene (`foxglove.SceneUpdate`), on two topics, so that the latest message of each
  (all that Foxglove and Lichtblick show after a seek) together hold the whole scene:
  * `scene/static`: the world's still entities (its visual markers, an object that does
    not move), once, at the session's first log time (no message without a world);
  * `scene`: the vehicle's body (a box with a heading arrow, locked to its frame, so it
    flies with the transforms) and the moving object, whole in every message: at the
    first log time, then each time the object has moved `OBJECT_STEP_M`.
* `call_log` (`foxglove.Log`): one line per service call made at the top (by the mission,
  the executive or a behavior; the calls nested inside it are in their own channels).
* `capability_state` (`aeroexec.CapabilityState`): `{name, references}` for each
  capability whose reference count changed, 0 when released: one series per capability
  for a State Transitions panel (`capability_state{name=="X"}.references`). The list of
  active capabilities cannot give it: a released capability is absent from the list, and
  the panel skips a message whose path yields nothing, so it would stay drawn as held.

Every message is complete (all the fields Foxglove's schema requires, primitive lists
empty when unused) and a pure function of its inputs, so recordings stay byte-identical.
Distances in metres, in the world's local ENU frame (x east, y north, z up).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from aeroexec.vehicles.world import MovingObject, World

#: The frame the vehicle's position is expressed in (local ENU, the simulator's world).
WORLD_FRAME = "world"
#: The derived topics (inside the drone's namespace).
TRANSFORM_TOPIC = "vehicle/transform"
SCENE_TOPIC = "scene"
STATIC_SCENE_TOPIC = "scene/static"
CALL_LOG_TOPIC = "call_log"
CAPABILITY_TOPIC = "capability_state"
#: A moving object's entity is sent again each time the object has moved this far (m):
#: half its size, a step the eye follows, at a cost that grows with its speed only.
OBJECT_STEP_M = 0.2

#: Colors (RGB, 0..255), shared with the Rerun view (aeroexec/viz/scene.py).
VEHICLE_COLOR = (66, 133, 244)
MARKER_COLOR = (40, 170, 90)
OBJECT_COLOR = (200, 60, 200)
#: Half sizes (m) of the vehicle's body box and of a marker's box.
BODY_HALF_SIZE = (0.25, 0.25, 0.06)
MARKER_HALF_SIZE = (0.1, 0.1, 0.1)
OBJECT_RADIUS = 0.2

LOG_INFO = 2
LOG_WARNING = 3
_NS = 1_000_000_000
_IDENTITY = {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}
_FOREVER = {"sec": 0, "nsec": 0}


def vehicle_frame(drone: str) -> str:
    """The frame of the vehicle's body (ROS's `base_link`, under the drone's namespace)."""
    return f"{drone}/base_link"


def stamp(log_time_ns: int) -> dict[str, int]:
    sec, nsec = divmod(max(log_time_ns, 0), _NS)
    return {"sec": sec, "nsec": nsec}


# -- the frame tree --------------------------------------------------------------------------
# A transform goes with every vehicle state whose pose changed (a third of a flying
# session's ticks): built with few calls, from locally bound functions.
_sin = math.sin
_cos = math.cos


def transform(
    x: float, y: float, z: float, yaw: float, log_time_ns: int, child_frame: str
) -> dict[str, Any] | None:
    """A `foxglove.FrameTransform` world -> `child_frame` (None if a value is not finite)."""
    # x - x is 0.0 for a finite x, NaN for an infinite or NaN one: one test for all four,
    # without a call each (a transform goes with a third of the states).
    if (x - x) + (y - y) + (z - z) + (yaw - yaw) != 0.0:
        return None
    sec, nsec = divmod(log_time_ns if log_time_ns > 0 else 0, _NS)
    half = yaw / 2
    return {
        "timestamp": {"sec": sec, "nsec": nsec},
        "parent_frame_id": WORLD_FRAME,
        "child_frame_id": child_frame,
        "translation": {"x": x, "y": y, "z": z},
        "rotation": {"x": 0.0, "y": 0.0, "z": _sin(half), "w": _cos(half)},
    }


# -- the scene -------------------------------------------------------------------------------
def _color(rgb: tuple[int, int, int], alpha: float = 1.0) -> dict[str, float]:
    r, g, b = rgb
    return {"r": r / 255, "g": g / 255, "b": b / 255, "a": alpha}


def _pose(x: float, y: float, z: float) -> dict[str, Any]:
    return {"position": {"x": x, "y": y, "z": z}, "orientation": dict(_IDENTITY)}


def _size(half: tuple[float, float, float]) -> dict[str, float]:
    return {"x": 2 * half[0], "y": 2 * half[1], "z": 2 * half[2]}


def _text(text: str, x: float, y: float, z: float) -> dict[str, Any]:
    return {
        "pose": _pose(x, y, z),
        "billboard": True,
        "font_size": 14.0,
        "scale_invariant": True,
        "color": _color((255, 255, 255)),
        "text": text,
    }


def _entity(
    log_time_ns: int,
    frame: str,
    entity_id: str,
    *,
    locked: bool = False,
    metadata: dict[str, str] | None = None,
    arrows: list[dict[str, Any]] | None = None,
    cubes: list[dict[str, Any]] | None = None,
    spheres: list[dict[str, Any]] | None = None,
    texts: list[dict[str, Any]] | None = None,
) -> dict[str, Any]:
    return {
        "timestamp": stamp(log_time_ns),
        "frame_id": frame,
        "id": entity_id,
        "lifetime": dict(_FOREVER),
        "frame_locked": locked,
        "metadata": [{"key": k, "value": v} for k, v in (metadata or {}).items()],
        "arrows": arrows or [],
        "cubes": cubes or [],
        "spheres": spheres or [],
        "cylinders": [],
        "lines": [],
        "triangles": [],
        "texts": texts or [],
        "models": [],
    }


def vehicle_entity(log_time_ns: int, drone: str) -> dict[str, Any]:
    """The vehicle's body in its own frame: it moves with the frame's transforms."""
    heading = {
        "pose": _pose(0.0, 0.0, 0.0),
        "shaft_length": 0.45,
        "shaft_diameter": 0.04,
        "head_length": 0.15,
        "head_diameter": 0.1,
        "color": _color((255, 200, 0)),
    }
    body = {
        "pose": _pose(0.0, 0.0, 0.0),
        "size": _size(BODY_HALF_SIZE),
        "color": _color(VEHICLE_COLOR),
    }
    return _entity(
        log_time_ns,
        vehicle_frame(drone),
        "vehicle",
        locked=True,
        metadata={"drone": drone},
        arrows=[heading],
        cubes=[body],
        texts=[_text(drone, 0.0, 0.0, 0.35)],
    )


def object_entity(log_time_ns: int, position: tuple[float, float, float]) -> dict[str, Any]:
    x, y, z = position
    sphere = {
        "pose": _pose(x, y, z + OBJECT_RADIUS),
        "size": {"x": 2 * OBJECT_RADIUS, "y": 2 * OBJECT_RADIUS, "z": 2 * OBJECT_RADIUS},
        "color": _color(OBJECT_COLOR),
    }
    return _entity(
        log_time_ns,
        WORLD_FRAME,
        "object",
        metadata={"kind": "object to follow"},
        spheres=[sphere],
        texts=[_text("object", x, y, z + 2 * OBJECT_RADIUS + 0.2)],
    )


def marker_entity(
    log_time_ns: int, marker_id: int, position: tuple[float, float, float]
) -> dict[str, Any]:
    x, y, z = position
    box = {"pose": _pose(x, y, z), "size": _size(MARKER_HALF_SIZE), "color": _color(MARKER_COLOR)}
    return _entity(
        log_time_ns,
        WORLD_FRAME,
        f"marker/{marker_id}",
        metadata={"kind": "visual marker", "marker_id": str(marker_id)},
        cubes=[box],
        texts=[_text(f"marker {marker_id}", x, y, z + 2 * MARKER_HALF_SIZE[2] + 0.15)],
    )


def object_moves(world: World | None) -> bool:
    return object_period_ns(world) is not None


def static_entities(log_time_ns: int, world: World) -> list[dict[str, Any]]:
    """The world's still entities: its visual markers (one entity each), and the object
    to follow when it stands still."""
    entities = [marker_entity(log_time_ns, m.id, m.position) for m in world.markers]
    if world.object is not None and not object_moves(world):
        entities.append(object_entity(log_time_ns, world.object.position))
    return entities


def moving_entities(log_time_ns: int, drone: str, world: World | None) -> list[dict[str, Any]]:
    """The vehicle, and the object to follow where it is at `log_time_ns` if it moves."""
    entities = [vehicle_entity(log_time_ns, drone)]
    if world is not None and world.object is not None and object_moves(world):
        entities.append(object_entity(log_time_ns, world.object.at(log_time_ns / _NS)))
    return entities


def scene_update(entities: list[dict[str, Any]]) -> dict[str, Any]:
    return {"deletions": [], "entities": entities}


def object_period_ns(world: World | None) -> int | None:
    """How often the object's entity is sent again: the time it takes to move
    OBJECT_STEP_M (None when there is no object or it stands still)."""
    if world is None or world.object is None:
        return None
    speed = math.hypot(*world.object.velocity)
    if speed <= 0 or not math.isfinite(speed):
        return None
    return max(1, round(OBJECT_STEP_M / speed * _NS))


class CapabilityChanges:
    """Each capability's reference count when it changes, from the successive
    `list_of_active_capabilities` payloads (in list order, then the released ones)."""

    __slots__ = ("_counts",)

    def __init__(self) -> None:
        self._counts: dict[str, int] = {}

    def update(self, payload: Mapping[str, Any]) -> list[dict[str, Any]]:
        # Once per activation: plain dicts are told apart by `type(...) is`, before
        # isinstance against the Mapping ABC.
        now: dict[str, int] = {}
        for item in payload.get("capabilities") or ():
            if type(item) is dict or isinstance(item, Mapping):
                name = item.get("name")
                if type(name) is str or isinstance(name, str):
                    references = item.get("references", 1)
                    now[name] = references if isinstance(references, int) else 1
        last = self._counts
        changes = [{"name": n, "references": c} for n, c in now.items() if last.get(n) != c]
        changes += [{"name": n, "references": 0} for n in last if n not in now]
        self._counts = now
        return changes


#: Where a derived message goes: (topic inside the namespace, log time, payload). The
#: payload is to be encoded, not changed or kept: the scenes share the vehicle's entity.
Emit = Callable[[str, int, dict[str, Any]], None]
#: A vehicle pose: x, y, z (m, ENU) and yaw (rad, counter-clockwise from east).
Pose = tuple[float, float, float, float]


#: The pose before the first: unequal to any a state holds (None included).
_UNSEEN = object()


class PanelFeed:
    """Derives the panels' messages from a session's own, in log-time order, and hands
    each to `emit` (the recorder writes them; a live stream can publish the same).

    `begin(t)` with the session's first log time writes the start: the static scene, the
    scene and, when `start_pose` is known, the vehicle's transform, so the 3D panel has
    the whole scene from the first instant. A caller that does not know the start pose
    need not call it: the start then comes with the first vehicle state."""

    __slots__ = (
        "_begun",
        "_body",
        "_capabilities",
        "_drone",
        "_due",
        "_emit",
        "_frame",
        "_last_position",
        "_last_yaw",
        "_moving",
        "_period",
        "_start",
        "_world",
    )

    def __init__(
        self, drone: str, emit: Emit, world: World | None = None, start_pose: Pose | None = None
    ) -> None:
        self._drone = drone
        self._world = world
        self._emit = emit
        self._frame = vehicle_frame(drone)
        #: The vehicle's entity but its timestamp (its first key).
        body = vehicle_entity(0, drone)
        del body["timestamp"]
        self._body = body
        self._start = start_pose
        self._begun = False
        #: The pose of the last transform sent, as a vehicle/state holds it: a state with
        #: the same pose sends none (Foxglove holds the latest transform).
        self._last_position: Any = _UNSEEN
        self._last_yaw: Any = _UNSEEN
        #: While an object moves: how often the scene is sent again, and when next.
        self._period = object_period_ns(world)
        self._moving: MovingObject | None = None
        if self._period is not None and world is not None:
            self._moving = world.object
        self._due: int | None = None
        self._capabilities = CapabilityChanges()

    def begin(self, log_time_ns: int) -> None:
        """The start, at the session's first log time (once; later calls do nothing)."""
        if self._begun:
            return
        self._begun = True
        emit = self._emit
        if self._world is not None:
            still = static_entities(log_time_ns, self._world)
            if still:
                emit(STATIC_SCENE_TOPIC, log_time_ns, scene_update(still))
        self._scene(log_time_ns)
        if self._start is not None:
            x, y, z, yaw = self._start
            frame = transform(x, y, z, yaw, log_time_ns, self._frame)
            if frame is not None:
                self._last_position, self._last_yaw = [x, y, z], yaw
                emit(TRANSFORM_TOPIC, log_time_ns, frame)

    def vehicle_state(self, state: Mapping[str, Any], log_time_ns: int) -> None:
        """A `vehicle/state`: its transform when the pose changed; the start if not yet
        sent; the scene again when the moving object is due."""
        if not self._begun:
            self.begin(log_time_ns)
        position = state.get("position")
        yaw = state.get("yaw")
        if position != self._last_position or yaw != self._last_yaw:
            self._last_position, self._last_yaw = position, yaw
            try:  # the state's pose; none if it has no usable one
                px, py, pz = position  # type: ignore[misc]
                frame = transform(
                    float(px),
                    float(py),
                    float(pz),
                    float(state.get("yaw", 0.0)),
                    log_time_ns,
                    self._frame,
                )
            except (TypeError, ValueError):
                frame = None
            if frame is not None:
                self._emit(TRANSFORM_TOPIC, log_time_ns, frame)
        due = self._due
        if due is not None and log_time_ns >= due:
            self._scene(log_time_ns)

    def call(self, call: Mapping[str, Any], log_time_ns: int) -> None:
        """A completed service call made at the top: its line in the call log."""
        self._emit(CALL_LOG_TOPIC, log_time_ns, call_log_message(call, log_time_ns))

    def capabilities(self, payload: Mapping[str, Any], log_time_ns: int) -> None:
        """A `list_of_active_capabilities`: a message per capability whose count changed."""
        for change in self._capabilities.update(payload):
            self._emit(CAPABILITY_TOPIC, log_time_ns, change)

    def _scene(self, log_time_ns: int) -> None:
        # moving_entities, with the vehicle's body built once: only its timestamp
        # changes (the payloads are encoded, never changed, so they may share it).
        entities = [{"timestamp": stamp(log_time_ns), **self._body}]
        moving = self._moving
        if moving is not None:  # where the object is now
            entities.append(object_entity(log_time_ns, moving.at(log_time_ns / _NS)))
        self._emit(SCENE_TOPIC, log_time_ns, scene_update(entities))
        period, due = self._period, self._due
        if period is None:
            return
        if due is None:
            self._due = log_time_ns + period
        else:  # on the period's grid (a state may come after a due time has passed)
            self._due = due + period * (1 + (log_time_ns - due) // period)


# -- the call log ----------------------------------------------------------------------------
# One line per top-level call: it runs once per activation, so the common types (exact
# str, int, float, bool, None, list, dict) are told apart by `type(...) is`, not by
# isinstance against the Mapping ABC; anything else takes the general path.
def _value(value: Any) -> str:
    kind = type(value)
    if kind is str:
        return value
    if kind is int:
        return str(value)
    if kind is float:
        return f"{value:g}"
    if kind is bool:
        return "true" if value else "false"
    if value is None:
        return "null"
    if kind is list or kind is tuple:
        return "[" + ", ".join([_value(v) for v in value]) + "]"
    if kind is dict:
        return "{" + ", ".join([f"{k}={_value(v)}" for k, v in value.items()]) + "}"
    return _any_value(value)


def _any_value(value: Any) -> str:
    if isinstance(value, str):
        return value
    if isinstance(value, bool) or value is None:
        return str(value).lower() if value is not None else "null"
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{k}={_value(v)}" for k, v in value.items()) + "}"
    return str(value)


#: Values `_fields` leaves out (compared by ==, so an empty tuple is kept).
_EMPTY: tuple[Any, ...] = ([], {}, "", None)
#: Types whose values never equal one of `_EMPTY`.
_NEVER_EMPTY = frozenset({int, float, bool})


def _fields(values: Mapping[str, Any], skip: tuple[str, ...] = ()) -> str:
    """`behavior` first and bare, `arguments` spread out, the rest as key=value
    (except the keys in `skip`)."""
    parts: list[str] = []
    behavior = values.get("behavior")
    if type(behavior) is str or isinstance(behavior, str):
        parts.append(behavior)
    for key, value in values.items():
        if key in skip:
            continue
        kind = type(value)
        if key == "behavior" and (kind is str or isinstance(value, str)):
            continue
        if key == "arguments" and (kind is dict or isinstance(value, Mapping)):
            parts += [f"{k}={_value(v)}" for k, v in value.items()]
            continue
        if kind is str or kind is list or kind is dict:
            if not value:
                continue
        elif value is None or (kind not in _NEVER_EMPTY and value in _EMPTY):
            continue
        parts.append(f"{key}={_value(value)}")
    return " ".join(parts)


_ANSWER_KEYS = ("ok", "error")


def call_log_message(call: Mapping[str, Any], log_time_ns: int) -> dict[str, Any]:
    """A top-level service call as one `foxglove.Log` line: `service request -> answer`."""
    request = call.get("request")
    response = call.get("response")
    if type(request) is not dict and not isinstance(request, Mapping):
        request = {}
    if type(response) is not dict and not isinstance(response, Mapping):
        response = {}
    ok = bool(response.get("ok"))
    asked = _fields(request)
    head = f"{call.get('service', '')} {asked}".rstrip()
    if ok:
        extra = _fields(response, _ANSWER_KEYS)
        answer = f"ok {extra}".rstrip()
    else:
        answer = f"refused: {response.get('error', '')}"
    return {
        "timestamp": stamp(log_time_ns),
        "level": LOG_INFO if ok else LOG_WARNING,
        "message": f"{head} -> {answer}",
        "name": str(call.get("caller", "")),
        "file": "",
        "line": 0,
    }
