"""Open-loop replay: the recorded external inputs into an executive with a new catalog.

For recordings of real flights (and imported bags) the world cannot be simulated again,
so the executive gets what came from outside it, at the recorded times: the mission's
commands (`CommandPlayer`), the vehicle state (`ReplayVehicle`, streamed from
`vehicle/state`) and how each behavior ended (`standins`: each stand-in ends with the
recorded code at the recorded time after its start, or is left to the catalog's timeout
and the replayed commands). What can change is what the executive decides: accepted or
rejected, preemptions, capabilities and processes, timeouts.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from aeroexec import __version__
from aeroexec.executive.bus import BusObserver
from aeroexec.executive.clock import SimClock, paced
from aeroexec.executive.executive import Executive
from aeroexec.mission.session import (
    end_observing,
    end_recording,
    mission_over,
    recording_session,
    session_observers,
    start_observing,
)
from aeroexec.plugins.discovery import BehaviorSet
from aeroexec.recording.tap import RecordTap
from aeroexec.replay.closedloop import ChosenCatalog, stopped_note
from aeroexec.replay.collect import STATE_TOPIC, OutcomeBuilder, OutcomeObserver, RecordedRun
from aeroexec.replay.outcome import RunOutcome
from aeroexec.replay.player import CommandPlayer
from aeroexec.replay.source import RecordingSource
from aeroexec.replay.standins import Script, stand_in_library
from aeroexec.replay.vehicle import ReplayVehicle


def replay_open(
    path: str | Path,
    run: RecordedRun,
    catalog: ChosenCatalog,
    behaviors: BehaviorSet,
    output: str | Path | None,
    horizon_ns: int | None,
    watchers: Sequence[BusObserver] = (),
    *,
    tap: RecordTap | None = None,
    speed: float | None = None,
) -> tuple[RunOutcome, tuple[str, ...]]:
    """Replay `run` (read from `path`) open loop; the replay's outcome and notes.
    `behaviors` answer the situation checks the recording has no answer for; `watchers`
    observe the replay's bus and session too (its progress, a live view: a viewer's
    abort stops the replay at that tick; the recorded vehicle takes no ending); `tap`
    sees its recording as it is written, `speed` paces its clock to the wall clock."""
    notes: list[str] = []
    recorded = run.outcome
    offset = recorded.start_ns or 0
    drone = run.metadata.get("drone") or "drone1"
    states = RecordingSource(path).scan(lambda name: name == STATE_TOPIC)
    clock = SimClock()
    vehicle = ReplayVehicle(states, clock, offset)
    script = Script(offset)
    builder = OutcomeBuilder(horizon_ns)
    metadata = {
        "aeroexec_version": __version__,
        "clock": "replay",
        "vehicle": vehicle.kind,
        "drone": drone,
        "catalog": catalog.name,
        "mission": "(mission/command stream)",
        "replay_of": Path(recorded.source).name,
        "replay_mode": "open",
        "time_offset_ns": str(offset),
    }
    _, observers, recorder = session_observers(
        output,
        drone,
        metadata,
        {"catalog.yaml": catalog.text},
        [OutcomeObserver(builder, offset_ns=offset), *watchers],
        start=vehicle.state(),
        tap=tap,
    )
    try:
        with recording_session(recorder):
            executive = Executive(
                catalog.catalog,
                vehicle=vehicle,
                clock=paced(clock, speed),
                library=stand_in_library(catalog.catalog, script, behaviors.library()),
                observers=observers,
                drone=drone,
            )
            start_observing(watchers, executive)
            player = CommandPlayer(executive, offset_ns=offset, arm=script.arm)
            stop = player.play(recorded.commands, until_ns=recorded.end_ns)
            mission_over(watchers, executive, stop is not None)
            end_observing(watchers, executive)
            ending, detail = "returned", "the recorded commands were replayed"
            if stop is not None:
                ending, detail = stop.by, stop.reason
                notes.append(stopped_note(stop, executive.now_s))
            if recorder is not None:
                end_recording(recorder, ending, detail, "")
    finally:
        states.close()
    if offset:
        notes.append(f"recorded times start at {offset / 1e9:.3f} s: the replay starts there")
    outcome = builder.outcome(f"{recorded.source} (open-loop replay)", metadata=dict(run.metadata))
    return outcome, tuple(notes)
