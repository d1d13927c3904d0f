"""A simulated session: catalog + world + seed + mission script -> outcome (+ recording).

`simulate()` is what `aeroexec run` does and what closed-loop replay does again with
another catalog; keeping it in one function is what makes "same inputs, same stream"
checkable.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from aeroexec import __version__
from aeroexec.catalog.loader import load_catalog
from aeroexec.catalog.model import Catalog
from aeroexec.catalog.paths import DEFAULT_CATALOG
from aeroexec.executive.bus import BusObserver
from aeroexec.executive.clock import SimClock
from aeroexec.executive.executive import Executive
from aeroexec.mission.activity import Activation, ActivityLog
from aeroexec.mission.api import MissionAPI
from aeroexec.mission.script import MissionOutcome, MissionScript, load_mission, run_script
from aeroexec.vehicles.base import VehicleState


@dataclass(frozen=True)
class SessionConfig:
    mission: str | Path
    catalog: str | Path = DEFAULT_CATALOG
    seed: int = 0
    world: str | Path | None = None
    record: str | Path | None = None
    drone: str = "drone1"


@dataclass(frozen=True)
class SessionResult:
    outcome: MissionOutcome
    activations: tuple[Activation, ...]
    duration_s: float
    final_state: VehicleState
    recording: str | None = None
    metadata: dict[str, str] = field(default_factory=dict)


def _build_vehicle(world_path: str | Path | None, seed: int):  # -> SimVehicle
    from aeroexec.vehicles.sim import SimVehicle
    from aeroexec.vehicles.world import default_world, load_world

    world = load_world(world_path) if world_path is not None else default_world()
    return SimVehicle(world, seed=seed)


def simulate(
    config: SessionConfig,
    observers: Iterable[BusObserver] = (),
    *,
    catalog: Catalog | None = None,
    script: MissionScript | None = None,
    catalog_text: str | None = None,
) -> SessionResult:
    """Run one mission in simulation. Unreadable inputs raise `AeroexecError`s before
    anything runs (and before any recording file is created)."""
    catalog = catalog if catalog is not None else load_catalog(config.catalog)
    script = script if script is not None else load_mission(config.mission)
    vehicle = _build_vehicle(config.world, config.seed)
    metadata = {
        "aeroexec_version": __version__,
        "seed": str(config.seed),
        "clock": "sim",
        "vehicle": vehicle.kind,
        "drone": config.drone,
        "catalog": Path(str(config.catalog)).name,
        "mission": Path(script.path).name,
        "world": Path(str(config.world)).name if config.world else "default",
    }
    activity = ActivityLog()
    all_observers: list[BusObserver] = [activity, *observers]
    recorder = None
    if config.record is not None:
        from aeroexec.recording import Recorder

        recorder = Recorder(
            config.record,
            drone=config.drone,
            metadata=metadata,
            attachments={
                "catalog.yaml": catalog_text if catalog_text is not None else catalog.text,
                "mission.py": script.text,
            },
        )
        all_observers.append(recorder)
    try:
        executive = Executive(
            catalog, vehicle=vehicle, clock=SimClock(), observers=all_observers, drone=config.drone
        )
        outcome = run_script(script, MissionAPI(executive))
    finally:
        if recorder is not None:
            recorder.close()
    return SessionResult(
        outcome=outcome,
        activations=tuple(activity.rows),
        duration_s=executive.now_s,
        final_state=vehicle.state(),
        recording=str(config.record) if config.record is not None else None,
        metadata=metadata,
    )
