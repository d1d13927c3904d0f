"""What the simulator flies in: visual markers, an object to follow, limits, failures.

A world is a YAML file (see `aeroexec/data/worlds/default.yaml`); every value is checked
and a bad one is reported as `WorldError` with the `file:line:col` of the offending
node, the same way catalog errors read. Numbers are SI: metres, seconds, m/s; angles in
world files are degrees because people write them that way.

Failures (`failures:` at a time, `random_failure:` at a seeded random one) are the kinds of
`aeroexec.vehicles.faults`, each with its parameters (`level`, `duration`, `speed`,
`direction`) written in that registry's units; a parameter left out takes its documented
default (docs/whatif.md#fault-kinds).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import lru_cache
from pathlib import Path
from typing import Any

from aeroexec.catalog.yamlnodes import YNode, load_yaml
from aeroexec.errors import CatalogError, Mark, WorldError
from aeroexec.inputs import read_text
from aeroexec.vehicles.base import Vec3
from aeroexec.vehicles.faults import FAULT_KINDS, KIND_NAMES, kinds_with, parameter_names

WORLDS_DIR = Path(__file__).resolve().parent.parent / "data" / "worlds"
DEFAULT_WORLD = WORLDS_DIR / "default.yaml"
FAULTS_WORLD = WORLDS_DIR / "faults.yaml"

#: Failure kinds the simulator can inject (the registry: `aeroexec.vehicles.faults`).
FAILURE_KINDS = KIND_NAMES
#: Visual marker ids are ArUco ids, as the catalog's UNTIL_OBSERVED_VISUAL_MARKER range says.
MAX_MARKER_ID = 1023


@dataclass(frozen=True, slots=True)
class Marker:
    id: int
    position: Vec3


@dataclass(frozen=True, slots=True)
class MovingObject:
    """Something to follow; it moves in a straight line at constant velocity."""

    position: Vec3
    velocity: Vec3 = (0.0, 0.0, 0.0)

    def at(self, t: float) -> Vec3:
        px, py, pz = self.position
        vx, vy, vz = self.velocity
        return (px + vx * t, py + vy * t, pz + vz * t)


@dataclass(frozen=True, slots=True)
class Limits:
    horizontal_speed: float = 2.0  # m/s
    vertical_speed: float = 1.0  # m/s
    acceleration: float = 2.0  # m/s², norm of the 3-D acceleration
    yaw_rate: float = 90.0  # degrees/s


@dataclass(frozen=True, slots=True)
class BatteryModel:
    initial: float = 1.0  # fraction of a full charge
    flight_endurance: float = 1200.0  # s of flight on a full charge (20 min)
    idle_endurance: float = 7200.0  # s on the ground on a full charge


def _value(failure: ScheduledFailure | RandomFailure, name: str) -> float:
    """A failure's parameter in the simulator's units: as given, else the kind's default."""
    given = getattr(failure, name)
    if given is not None:
        return float(given)
    parameter = FAULT_KINDS[failure.kind].parameter(name)
    return 0.0 if parameter is None else parameter.default * parameter.scale


@dataclass(frozen=True, slots=True)
class ScheduledFailure:
    """A failure at `at` seconds: it strikes at the end of the first simulator step that
    reaches that time. Parameters (aeroexec/vehicles/faults.py) in the simulator's units;
    None: the kind's default."""

    kind: str
    at: float  # seconds of simulated time
    #: For `low_battery`: the charge the battery drops to (fraction).
    level: float = 0.10
    #: For `lost_link`, `lost_position`, `wind_gust`: how long it lasts (s).
    duration: float | None = None
    #: For `wind_gust`: the wind's speed (m/s) and where it blows toward (degrees).
    speed: float | None = None
    direction: float | None = None

    def value(self, name: str) -> float:
        return _value(self, name)


@dataclass(frozen=True, slots=True)
class RandomFailure:
    """A failure that strikes with `rate` per second (a Poisson process), drawn from
    `random.Random(seed)`; `seed` None means the world's (or the vehicle's) seed."""

    kind: str
    rate: float
    seed: int | None = None
    level: float = 0.10
    duration: float | None = None
    speed: float | None = None
    direction: float | None = None

    def value(self, name: str) -> float:
        return _value(self, name)


@dataclass(frozen=True, slots=True)
class World:
    name: str = "empty"
    markers: tuple[Marker, ...] = ()
    object: MovingObject | None = None
    camera_range: float = 4.0  # m, horizontal distance
    start: Vec3 = (0.0, 0.0, 0.0)
    start_yaw: float = 0.0  # degrees
    limits: Limits = field(default_factory=Limits)
    battery: BatteryModel = field(default_factory=BatteryModel)
    failures: tuple[ScheduledFailure, ...] = ()
    random_failure: RandomFailure | None = None
    seed: int = 0


# -- reading ------------------------------------------------------------------------------


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


class _Reader:
    """Typed accessors over marked YAML nodes; each failure names the node's place."""

    def __init__(self, file: str) -> None:
        self.file = file

    def fail(self, message: str, node: YNode | Mark) -> WorldError:
        return WorldError(message, node if isinstance(node, Mark) else node.mark)

    def mapping(self, node: YNode, what: str, known: tuple[str, ...]) -> dict[str, YNode]:
        if not node.is_map:
            raise self.fail(f"{what} must be a mapping, got {_kind(node)}", node)
        if node.duplicate_keys:
            key, mark = node.duplicate_keys[0]
            raise self.fail(f"{what}: '{key}' is given twice", mark)
        for key in node.value:
            if key not in known:
                raise self.fail(
                    f"{what}: unknown key '{key}' (known: {', '.join(known)})",
                    node.key_marks[key],
                )
        return node.value

    def number(
        self,
        node: YNode,
        what: str,
        *,
        minimum: float | None = None,
        maximum: float | None = None,
        positive: bool = False,
    ) -> float:
        value = node.value
        if not _is_number(value) or not math.isfinite(value):
            raise self.fail(f"{what} must be a number, got {_show(node)}", node)
        if positive and value <= 0:
            raise self.fail(f"{what} must be positive, got {value:g}", node)
        if minimum is not None and value < minimum:
            raise self.fail(f"{what} must be at least {minimum:g}, got {value:g}", node)
        if maximum is not None and value > maximum:
            raise self.fail(f"{what} must be at most {maximum:g}, got {value:g}", node)
        return float(value)

    def integer(self, node: YNode, what: str, minimum: int, maximum: int) -> int:
        value = node.value
        if not isinstance(value, int) or isinstance(value, bool):
            raise self.fail(f"{what} must be an integer, got {_show(node)}", node)
        if not minimum <= value <= maximum:
            raise self.fail(f"{what} must be in [{minimum}, {maximum}], got {value}", node)
        return value

    def vector(self, node: YNode, what: str) -> Vec3:
        if not node.is_list or len(node.value) != 3:
            raise self.fail(
                f"{what} must be a list of 3 numbers [x, y, z], got {_show(node)}", node
            )
        x, y, z = (self.number(item, what) for item in node.value)
        return (x, y, z)

    def text(self, node: YNode, what: str) -> str:
        if not isinstance(node.value, str) or not node.value:
            raise self.fail(f"{what} must be text, got {_show(node)}", node)
        return node.value

    def kind(self, node: YNode, what: str) -> str:
        kind = self.text(node, what)
        if kind not in FAILURE_KINDS:
            raise self.fail(
                f"{what}: unknown failure kind '{kind}' (known: {', '.join(FAILURE_KINDS)})", node
            )
        return kind

    def parameters(self, entry: dict[str, YNode], kind: str, what: str) -> dict[str, float]:
        """The fault parameters of a failure entry, in the simulator's units; a parameter
        of another kind is an error at its key."""
        values: dict[str, float] = {}
        for name in parameter_names():
            if name not in entry:
                continue
            parameter = FAULT_KINDS[kind].parameter(name)
            if parameter is None:
                raise self.fail(
                    f"{what}: '{name}' applies to {', '.join(kinds_with(name))} only",
                    entry[name],
                )
            written = self.number(
                entry[name],
                f"{what}.{name} ({parameter.unit})",
                minimum=parameter.minimum,
                maximum=parameter.maximum,
            )
            values[name] = written * parameter.scale
        return values


def _kind(node: YNode) -> str:
    if node.is_map:
        return "a mapping"
    if node.is_list:
        return "a list"
    return _show(node)


def _show(node: YNode) -> str:
    value = node.plain()
    return "nothing" if value is None else repr(value)


_TOP_KEYS = (
    "name",
    "seed",
    "camera",
    "vehicle",
    "battery",
    "markers",
    "object",
    "failures",
    "random_failure",
)


def parse_world(text: str, file: str = "<string>") -> World:
    """Build a `World` from YAML text; raises `WorldError` with the place of the problem."""
    try:
        root = load_yaml(text, file)
    except CatalogError as exc:  # the YAML layer is shared with catalogs; re-badge its errors
        raise WorldError(exc.message, exc.mark) from None
    if root is None:
        return World()
    r = _Reader(file)
    top = r.mapping(root, "world", _TOP_KEYS)
    settings: dict[str, Any] = {}
    if "name" in top:
        settings["name"] = r.text(top["name"], "name")
    if "seed" in top:
        settings["seed"] = r.integer(top["seed"], "seed", 0, 2**63 - 1)
    if "camera" in top:
        camera = r.mapping(top["camera"], "camera", ("range",))
        if "range" in camera:
            settings["camera_range"] = r.number(camera["range"], "camera.range", positive=True)
    if "vehicle" in top:
        settings.update(_vehicle(r, top["vehicle"]))
    if "battery" in top:
        settings["battery"] = _battery(r, top["battery"])
    if "markers" in top:
        settings["markers"] = _markers(r, top["markers"])
    if "object" in top and top["object"].value is not None:
        obj = r.mapping(top["object"], "object", ("position", "velocity"))
        if "position" not in obj:
            raise r.fail("object needs a position", top["object"])
        velocity = r.vector(obj["velocity"], "object.velocity") if "velocity" in obj else None
        settings["object"] = MovingObject(
            r.vector(obj["position"], "object.position"), velocity or (0.0, 0.0, 0.0)
        )
    if "failures" in top:
        settings["failures"] = _failures(r, top["failures"])
    if "random_failure" in top and top["random_failure"].value is not None:
        settings["random_failure"] = _random_failure(r, top["random_failure"])
    return World(**settings)


def _vehicle(r: _Reader, node: YNode) -> dict[str, Any]:
    keys = (
        "start",
        "start_yaw",
        "max_horizontal_speed",
        "max_vertical_speed",
        "max_acceleration",
        "max_yaw_rate",
    )
    vehicle = r.mapping(node, "vehicle", keys)
    out: dict[str, Any] = {}
    if "start" in vehicle:
        start = r.vector(vehicle["start"], "vehicle.start")
        if start[2] != 0:
            raise r.fail("vehicle.start must be on the ground (z = 0)", vehicle["start"])
        out["start"] = start
    if "start_yaw" in vehicle:
        out["start_yaw"] = r.number(
            vehicle["start_yaw"], "vehicle.start_yaw", minimum=-360, maximum=360
        )
    defaults = Limits()
    out["limits"] = Limits(
        *(
            r.number(vehicle[key], f"vehicle.{key}", positive=True)
            if key in vehicle
            else getattr(defaults, attr)
            for key, attr in (
                ("max_horizontal_speed", "horizontal_speed"),
                ("max_vertical_speed", "vertical_speed"),
                ("max_acceleration", "acceleration"),
                ("max_yaw_rate", "yaw_rate"),
            )
        )
    )
    return out


def _battery(r: _Reader, node: YNode) -> BatteryModel:
    battery = r.mapping(node, "battery", ("initial", "flight_endurance", "idle_endurance"))
    defaults = BatteryModel()
    return BatteryModel(
        initial=(
            r.number(battery["initial"], "battery.initial (percent)", minimum=0, maximum=100)
            / 100.0
            if "initial" in battery
            else defaults.initial
        ),
        flight_endurance=(
            r.number(battery["flight_endurance"], "battery.flight_endurance", positive=True)
            if "flight_endurance" in battery
            else defaults.flight_endurance
        ),
        idle_endurance=(
            r.number(battery["idle_endurance"], "battery.idle_endurance", positive=True)
            if "idle_endurance" in battery
            else defaults.idle_endurance
        ),
    )


def _markers(r: _Reader, node: YNode) -> tuple[Marker, ...]:
    if node.value is None:
        return ()
    if not node.is_list:
        raise r.fail(f"markers must be a list, got {_kind(node)}", node)
    markers: list[Marker] = []
    seen: dict[int, Mark] = {}
    for item in node.value:
        entry = r.mapping(item, "marker", ("id", "position"))
        for key in ("id", "position"):
            if key not in entry:
                raise r.fail(f"marker needs '{key}'", item)
        marker_id = r.integer(entry["id"], "marker id", 0, MAX_MARKER_ID)
        if marker_id in seen:
            first = seen[marker_id]
            raise r.fail(
                f"marker id {marker_id} is used twice (first at line {first.line})",
                entry["id"],
            )
        seen[marker_id] = entry["id"].mark
        markers.append(Marker(marker_id, r.vector(entry["position"], "marker position")))
    # Ascending ids, so what the camera reports never depends on the file's order.
    return tuple(sorted(markers, key=lambda m: m.id))


def _failures(r: _Reader, node: YNode) -> tuple[ScheduledFailure, ...]:
    if node.value is None:
        return ()
    if not node.is_list:
        raise r.fail(f"failures must be a list, got {_kind(node)}", node)
    failures: list[ScheduledFailure] = []
    for item in node.value:
        entry = r.mapping(item, "failure", ("kind", "at", *parameter_names()))
        for key in ("kind", "at"):
            if key not in entry:
                raise r.fail(f"failure needs '{key}'", item)
        kind = r.kind(entry["kind"], "failure")
        values = r.parameters(entry, kind, "failure")
        failures.append(
            ScheduledFailure(
                kind, r.number(entry["at"], "failure.at (seconds)", minimum=0), **values
            )
        )
    # Stable by time then file order: two failures at the same time strike in file order.
    return tuple(sorted(failures, key=lambda f: f.at))


def _random_failure(r: _Reader, node: YNode) -> RandomFailure:
    entry = r.mapping(node, "random_failure", ("kind", "rate", "seed", *parameter_names()))
    for key in ("kind", "rate"):
        if key not in entry:
            raise r.fail(f"random_failure needs '{key}'", node)
    kind = r.kind(entry["kind"], "random_failure")
    values = r.parameters(entry, kind, "random_failure")
    return RandomFailure(
        kind,
        r.number(entry["rate"], "random_failure.rate (per second)", minimum=0),
        r.integer(entry["seed"], "random_failure.seed", 0, 2**63 - 1) if "seed" in entry else None,
        **values,
    )


def with_failures(world: World, failures: tuple[ScheduledFailure, ...]) -> World:
    """`world` with `failures` struck besides its own (in time order; at the same time,
    the world's first)."""
    if not failures:
        return world
    merged = sorted((*world.failures, *failures), key=lambda f: f.at)
    return replace(world, failures=tuple(merged))


def load_world(path: str | Path) -> World:
    """Read a world file; unreadable files are a `WorldError` too."""
    return parse_world(read_text(path, "a world file", WorldError), str(path))


@lru_cache(maxsize=1)
def default_world() -> World:
    """The shipped world the Appendix C mission flies in (shared: worlds are immutable)."""
    return load_world(DEFAULT_WORLD)
