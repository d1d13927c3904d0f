"""A simulated session: catalog + world + seed + mission script -> outcome (+ recording).

`simulate()` is what `aeroexec run` does and what closed-loop replay does again with
another catalog; keeping it in one function is what makes "same inputs, same stream"
checkable.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

from aeroexec import __version__
from aeroexec.catalog.loader import load_catalog
from aeroexec.catalog.model import Catalog
from aeroexec.catalog.paths import DEFAULT_CATALOG
from aeroexec.executive.behavior import Behavior
from aeroexec.executive.bus import BusObserver
from aeroexec.executive.clock import NS_PER_S, SimClock, paced
from aeroexec.executive.executive import Executive
from aeroexec.inputs import read_text
from aeroexec.interrupts import Interrupted
from aeroexec.mission.activity import Activation, ActivityLog
from aeroexec.mission.api import MissionAPI
from aeroexec.mission.assurance import carry_out
from aeroexec.mission.script import (
    MissionOutcome,
    MissionScript,
    load_mission,
    run_script,
)
from aeroexec.plugins.discovery import STAND_IN, BehaviorSet, standard_set
from aeroexec.plugins.manifest import code_manifest
from aeroexec.recording.schemas import CODE_METADATA_NAME as CODE_RECORD
from aeroexec.vehicles.base import Vehicle, VehicleState
from aeroexec.vehicles.sim import SimVehicle

if TYPE_CHECKING:
    from aeroexec.recording import Recorder
    from aeroexec.recording.tap import RecordTap
    from aeroexec.vehicles.world import ScheduledFailure, World


#: A mission that never ends is stopped after one simulated day.
DEFAULT_MAX_SIM_TIME_S = 24 * 3600.0


@dataclass(frozen=True)
class SessionConfig:
    mission: str | Path
    catalog: str | Path = DEFAULT_CATALOG
    seed: int = 0
    world: str | Path | None = None
    record: str | Path | None = None
    drone: str = "drone1"
    #: The behaviors to run with (default: the standard library).
    behaviors: BehaviorSet | None = None
    #: Run catalog behaviors without an implementation as announced stand-ins.
    allow_unimplemented: bool = False
    #: The session ends when the simulated clock reaches this (None: never).
    max_sim_time_s: float | None = DEFAULT_MAX_SIM_TIME_S
    #: Failures struck into the world besides its own (`replay --inject`), and the
    #: metadata that records them.
    injected: tuple[ScheduledFailure, ...] = ()
    injected_metadata: Mapping[str, str] = field(default_factory=dict)
    #: Where the vehicle starts instead of the world's: (x, y, yaw in degrees), on the
    #: ground (a flight's simulated twin starts where the flight did).
    start: tuple[float, float, float] | None = None
    #: Sees the recording as it is written (a live view); it is recorded even without
    #: `record` (to no file).
    tap: RecordTap | None = None
    #: Keep the simulated clock to the wall clock at this factor (None: as fast as it runs).
    speed: float | None = None


@dataclass(frozen=True)
class SessionResult:
    outcome: MissionOutcome
    activations: tuple[Activation, ...]
    duration_s: float
    final_state: VehicleState
    recording: str | None = None
    metadata: dict[str, str] = field(default_factory=dict)
    #: (clock ns, fault) each time the vehicle's fault changed ('' when it cleared).
    faults: tuple[tuple[int, str], ...] = ()
    #: What ended the flight after a violated property's action (`run --spec`).
    assurance: tuple[str, ...] = ()

    @property
    def vehicle_lost(self) -> str:
        """The fault the vehicle ended the session with ('' when it ended healthy)."""
        return self.final_state.fault


def _world_text(world_path: str | Path | None) -> tuple[str, str]:
    """The world file's text and the name to show: recorded so replay can rebuild it."""
    from aeroexec.errors import WorldError
    from aeroexec.vehicles.world import DEFAULT_WORLD

    path = Path(world_path) if world_path is not None else DEFAULT_WORLD
    return read_text(path, "a world file", WorldError), str(path)


#: The metadata key of a session that started elsewhere than its world's start.
START = "start"


def start_metadata(start: tuple[float, float, float] | None) -> dict[str, str]:
    """`start=x,y,yaw` (exact floats), or nothing for the world's own start."""
    return {START: ",".join(repr(float(v)) for v in start)} if start is not None else {}


def recorded_start(metadata: Mapping[str, str]) -> tuple[float, float, float] | None:
    """The start a session recorded (`start_metadata`), or None (also for a malformed
    value: the world's start, as for a recording without one)."""
    text = metadata.get(START)
    if not text:
        return None
    try:
        x, y, yaw = (float(v) for v in text.split(","))
    except ValueError:
        return None
    return (x, y, yaw)


def placed(world: World, start: tuple[float, float, float] | None) -> World:
    """`world` with the vehicle starting at `start` (x, y, yaw degrees) on the ground."""
    if start is None:
        return world
    return replace(world, start=(start[0], start[1], 0.0), start_yaw=start[2])


def _build_vehicle(world_text: str, world_file: str, config: SessionConfig) -> SimVehicle:
    from aeroexec.vehicles.world import parse_world, with_failures

    world = with_failures(parse_world(world_text, world_file), config.injected)
    return SimVehicle(placed(world, config.start), seed=config.seed)


def session_observers(
    record: str | Path | None,
    drone: str,
    metadata: dict[str, str],
    attachments: dict[str, str],
    observers: Iterable[BusObserver],
    records: Mapping[str, Mapping[str, str]] | None = None,
    world: World | None = None,
    start: VehicleState | None = None,
    tap: RecordTap | None = None,
    *,
    live: bool = False,
) -> tuple[ActivityLog, list[BusObserver], Recorder | None]:
    """The observers every session has: its activity log, the caller's, and the
    recorder when one is asked for (the caller closes it). `world`: what the vehicle
    flies in, drawn in the recording's 3D scene; `start`: the vehicle's state the session
    starts from, whose pose places the vehicle in that scene from the first instant;
    `tap`: sees the recording as it is written (without `record`, the session is
    recorded to no file for it). `live`: the session runs on the wall clock (a flight),
    so its recording also keeps the time flush bound (a crash loses at most 0.5 s of
    it); a simulated session's is bounded by message count and size only
    (docs/recording.md)."""
    activity = ActivityLog()
    everyone: list[BusObserver] = [activity, *observers]
    recorder = None
    if record is not None or tap is not None:
        from aeroexec.recording import FLUSH_INTERVAL_NS, Recorder

        recorder = Recorder(
            record if record is not None else os.devnull,
            drone=drone,
            metadata=metadata,
            attachments=attachments,
            records=records,
            world=world,
            start_pose=(*start.position, start.yaw) if start is not None else None,
            flush_interval_ns=FLUSH_INTERVAL_NS if live else None,
            tap=tap,
        )
        everyone.append(recorder)
    return activity, everyone, recorder


@dataclass(frozen=True, slots=True)
class SessionCode:
    """The behaviors a session runs, and what its recording says about them."""

    behaviors: BehaviorSet
    #: The `behaviors` metadata record (per behavior: module:Class and source hash).
    records: dict[str, dict[str, str]]
    #: The developer's behavior sources, as attachments.
    attachments: dict[str, str]

    @property
    def library(self) -> dict[str, type[Behavior]]:
        return self.behaviors.library()


def session_code(
    catalog: Catalog,
    behaviors: BehaviorSet | None,
    allow_unimplemented: bool,
    announce: Callable[[str], None] | None = None,
) -> SessionCode:
    """Compose the behavior library for `catalog`: `BehaviorError` (before anything runs
    or any file is created) when a catalog behavior has no implementation, unless
    `allow_unimplemented`; then each stand-in is announced once, here."""
    chosen = (behaviors or standard_set()).for_catalog(catalog, allow_unimplemented)
    if announce is not None:
        for name in chosen.stand_ins:
            announce(
                f"warning: {name} has no implementation: a stand-in "
                f"({STAND_IN.__name__}) ends it with GOAL_ACHIEVED after "
                f"{STAND_IN.duration:g} s"
            )
    manifest = code_manifest(chosen, catalog)
    return SessionCode(chosen, {CODE_RECORD: manifest.metadata()}, manifest.attachments())


def stand_in_metadata(code: SessionCode) -> dict[str, str]:
    """The session metadata that marks stand-ins (nothing when there are none)."""
    names = code.behaviors.stand_ins
    return {"stand_ins": ",".join(names)} if names else {}


def simulate(
    config: SessionConfig,
    observers: Iterable[BusObserver] = (),
    *,
    catalog: Catalog | None = None,
    script: MissionScript | None = None,
    catalog_text: str | None = None,
    world: tuple[str, str] | None = None,
    announce: Callable[[str], None] | None = None,
) -> SessionResult:
    """Run one mission in simulation. Unreadable inputs, and catalog behaviors without
    an implementation, raise `AeroexecError`s before anything runs (and before any
    recording file is created).

    `catalog`, `script` and `world` ((text, name)) override what `config` names: replay
    passes the ones recorded in a session's attachments. `announce` is told each
    stand-in (with `config.allow_unimplemented`) once, before the session starts."""
    observers = list(observers)
    catalog = catalog if catalog is not None else load_catalog(config.catalog)
    script = script if script is not None else load_mission(config.mission)
    code = session_code(catalog, config.behaviors, config.allow_unimplemented, announce)
    world_text, world_file = world if world is not None else _world_text(config.world)
    vehicle = _build_vehicle(world_text, world_file, config)
    metadata = {
        "aeroexec_version": __version__,
        "seed": str(config.seed),
        "clock": "sim",
        "vehicle": vehicle.kind,
        "drone": config.drone,
        "catalog": Path(str(config.catalog)).name,
        "mission": Path(script.path).name,
        "world": Path(str(config.world)).name if config.world else "default",
        **stand_in_metadata(code),
        **start_metadata(config.start),
        **config.injected_metadata,
    }
    attachments = {
        "catalog.yaml": catalog_text if catalog_text is not None else catalog.text,
        "mission.py": script.text,
        "world.yaml": world_text,
        **code.attachments,
    }
    activity, all_observers, recorder = session_observers(
        config.record,
        config.drone,
        metadata,
        attachments,
        observers,
        code.records,
        vehicle.world,
        vehicle.state(),
        config.tap,
    )
    with recording_session(recorder, vehicle):
        executive = Executive(
            catalog,
            vehicle=vehicle,
            clock=paced(SimClock(), config.speed),
            library=code.library,
            observers=all_observers,
            drone=config.drone,
        )
        if config.max_sim_time_s is not None:
            executive.time_limit_ns = round(config.max_sim_time_s * NS_PER_S)
        start_observing(observers, executive)
        api = MissionAPI(executive)
        outcome = run_script(script, api)
        mission_over(observers, executive, outcome.ending.stopped)
        assurance: list[str] = []
        if outcome.ending.stopped and executive.stop_request is not None:
            start = vehicle.world.start
            assurance = carry_out(
                executive, api, vehicle, executive.stop_request[1], (start[0], start[1])
            )
        end_observing(observers, executive)
        if recorder is not None:
            end_recording(recorder, outcome.ending.value, outcome.error, vehicle.state().fault)
    return SessionResult(
        outcome=outcome,
        activations=tuple(activity.rows),
        duration_s=executive.now_s,
        final_state=vehicle.state(),
        recording=str(config.record) if config.record is not None else None,
        metadata=metadata,
        faults=tuple(activity.faults),
        assurance=tuple(assurance),
    )


def start_observing(observers: Iterable[BusObserver], executive: Executive) -> None:
    """Hand the executive to the observers that act on it (a property monitor asks it to
    stop with `request_stop`): those with a `session_started(executive)` method."""
    for observer in observers:
        started = getattr(observer, "session_started", None)
        if started is not None:
            started(executive)


def mission_over(observers: Iterable[BusObserver], executive: Executive, stopped: bool) -> None:
    """The mission script is over, the ending comes: observers with a `mission_ended()`
    method hear it (a live view takes no more aborts). A stop asked for now, when the
    mission was not stopped, is dropped: the ending steps on."""
    for observer in observers:
        ended = getattr(observer, "mission_ended", None)
        if ended is not None:
            ended()
    if not stopped:
        executive.stop_request = None


def end_observing(observers: Iterable[BusObserver], executive: Executive) -> None:
    """Tell those observers the session ends, while it can still publish (and record)."""
    for observer in observers:
        ending = getattr(observer, "session_ending", None)
        if ending is not None:
            ending(executive)


@contextmanager
def recording_session(recorder: Recorder | None, vehicle: Vehicle | None = None) -> Iterator[None]:
    """The block a recorded session runs in: on a signal the recording gets its end
    record ("interrupted") and its footer, and the `Interrupted` says so; however the
    block ends, the recorder is closed."""
    try:
        yield
    except Interrupted as stop:
        if recorder is not None and not recorder.closed:
            fault = vehicle.state().fault if vehicle is not None else ""
            end_recording(recorder, "interrupted", stop.name, fault)
            if str(recorder.path) != os.devnull:  # recorded for a live view only
                stop.notes.append(finalized_note(recorder))
        raise
    finally:
        if recorder is not None and not recorder.closed:
            recorder.close()


def finalized_note(recorder: Recorder) -> str:
    """What an interrupted command says about its recording."""
    return recorder.finalized_note()


def end_recording(recorder: Recorder, reason: str, detail: str, fault: str) -> None:
    """Write why the session ended (`aeroexec_end`), then the footer."""
    facts = {"vehicle_fault": fault} if fault else {}
    recorder.end_session(reason, detail, **facts)
    recorder.close()
