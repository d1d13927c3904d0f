"""Closed-loop replay: run the recorded mission again, in the simulator.

The recording carries everything a simulated session was made of: the mission script
(`mission.py`), the world (`world.yaml`), the seed and the drone name (metadata). Replay
hands them to `aeroexec.mission.session.simulate` with the chosen catalog — the very
function `aeroexec run` uses — so with the recorded catalog and unchanged code the replay
is the same session again, message for message and, when recorded with the same
settings, byte for byte.

The script is code, and a recording is data a user may have received from anyone: the
stored script runs only with `--trust-recording`. With `--mission PATH` the user's own
copy runs instead (noted when it differs from the stored one). With neither, or for a
recording without a script, the `mission/command` stream is replayed (`CommandPlayer`,
commands at their recorded times, each waiting for the end of a previous
`execute_behavior` as the script did): the same commands, no code from the file.
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from aeroexec import __version__
from aeroexec.catalog.model import Catalog
from aeroexec.executive.bus import BusObserver
from aeroexec.executive.clock import SimClock, paced
from aeroexec.executive.executive import Executive, StopRequested
from aeroexec.mission.api import MissionAPI
from aeroexec.mission.assurance import carry_out
from aeroexec.mission.script import MissionScript, compile_mission
from aeroexec.mission.session import (
    SessionConfig,
    end_observing,
    end_recording,
    mission_over,
    placed,
    recorded_start,
    recording_session,
    session_code,
    session_observers,
    simulate,
    stand_in_metadata,
    start_metadata,
    start_observing,
)
from aeroexec.plugins.discovery import BehaviorSet
from aeroexec.recording.reader import attachment_place
from aeroexec.recording.tap import RecordTap
from aeroexec.replay.collect import OutcomeBuilder, OutcomeObserver, RecordedRun
from aeroexec.replay.outcome import RunOutcome
from aeroexec.replay.player import CommandPlayer
from aeroexec.vehicles.sim import SimVehicle
from aeroexec.vehicles.world import DEFAULT_WORLD, ScheduledFailure, parse_world, with_failures


@dataclass(frozen=True, slots=True)
class ChosenCatalog:
    """The catalog a replay runs with: the loaded model, its exact text (recorded as the
    replay's attachment) and the name the session metadata shows."""

    catalog: Catalog
    text: str
    name: str


@dataclass(frozen=True, slots=True)
class _Injected:
    """Failures a replay strikes besides the world's own, and their metadata record;
    where the vehicle starts; the live view's tap and pacing."""

    faults: tuple[ScheduledFailure, ...]
    metadata: dict[str, str]
    start: tuple[float, float, float] | None = None
    tap: RecordTap | None = None
    speed: float | None = None


class _Discard(io.TextIOBase):
    """Where a replayed mission's prints go (the report says what matters)."""

    def write(self, text: str) -> int:
        return len(text)


def mission_prints_discarded() -> contextlib.redirect_stdout[io.TextIOBase]:
    """The block a replayed mission runs in: its prints go nowhere."""
    return contextlib.redirect_stdout(_Discard())


def _seed(metadata: dict[str, str], notes: list[str]) -> int:
    try:
        return int(metadata.get("seed", "0"))
    except ValueError:
        notes.append(f"seed {metadata.get('seed')!r} is not an integer: replayed with seed 0")
        return 0


def _world(run: RecordedRun, notes: list[str]) -> tuple[str, str]:
    """The world's text and its name (as the recording's metadata gives it: the session
    records it again). The attachment is checked here, where its errors are marked as
    the recording's (`REC#world.yaml:LINE:COL`): a tampered world is the recording's
    fault, not that of the world file it was once copied from."""
    name = run.metadata.get("world") or "default"
    text = run.text("world.yaml")
    if text is None:
        notes.append("no world.yaml attachment: replayed in the default world")
        return DEFAULT_WORLD.read_text(encoding="utf-8"), "default"
    parse_world(text, attachment_place(run.outcome.source, "world.yaml"))
    return text, name


#: Why closed loop did not run the script stored in a recording.
UNTRUSTED = (
    "the recording's mission.py was not run (--trust-recording runs it, --mission FILE "
    "runs yours): replayed the recorded mission commands"
)


def script_to_run(
    run: RecordedRun, mission: MissionScript | None, trust_recording: bool, notes: list[str]
) -> MissionScript | None:
    """The mission script closed loop runs, or None to replay the command stream.

    A recording is data anyone may send: the script stored in it is run only when the
    user says so (`trust_recording`); otherwise the user's own script (`mission`) runs,
    or, without one, the recorded commands are replayed and no code from the file is."""
    recorded = run.text("mission.py")
    if mission is not None:
        if recorded is None:
            notes.append(f"ran {mission.path}; the recording has no mission.py to compare with")
        elif recorded != mission.text:
            notes.append(f"ran {mission.path}, which differs from the recording's mission.py")
        return mission
    if recorded is None:
        notes.append("no mission.py attachment: replayed the recorded mission/command stream")
        return None
    if not trust_recording:
        notes.append(UNTRUSTED)
        return None
    return compile_mission(recorded, run.metadata.get("mission") or "mission.py")


def replay_closed(
    run: RecordedRun,
    catalog: ChosenCatalog,
    behaviors: BehaviorSet,
    output: str | Path | None,
    horizon_ns: int | None,
    *,
    mission: MissionScript | None = None,
    trust_recording: bool = False,
    watchers: Sequence[BusObserver] = (),
    faults: tuple[ScheduledFailure, ...] = (),
    faults_metadata: Mapping[str, str] | None = None,
    start: tuple[float, float, float] | None = None,
    tap: RecordTap | None = None,
    speed: float | None = None,
) -> tuple[RunOutcome, tuple[str, ...]]:
    """Replay `run` in the simulator with `behaviors` (complete for the catalog, stand-ins
    included); the replay's outcome and notes about how.

    `mission`: the script to run (the user's copy); `trust_recording`: without one, run
    the script stored in the recording. Neither: the recorded command stream is replayed
    and no code from the recording runs. `watchers` observe the replay's bus too (its
    progress). `faults` strike besides the world's own (`--inject`), and
    `faults_metadata` records them. `start` (x, y, yaw degrees): where the vehicle
    starts instead of the world's start (a flight's twin; a recording that says so).
    `tap` sees the replay's recording as it is written (a live view), and `speed` keeps
    its clock to the wall clock (`ReplayOptions.speed`), as `run --live` does."""
    notes: list[str] = []
    metadata = run.metadata
    seed = _seed(metadata, notes)
    world = _world(run, notes)
    drone = metadata.get("drone") or "drone1"
    builder = OutcomeBuilder(horizon_ns)
    observer = OutcomeObserver(builder)
    script = script_to_run(run, mission, trust_recording, notes)
    start = start if start is not None else recorded_start(metadata)
    injected = _Injected(faults, dict(faults_metadata or {}), start, tap, speed)
    if script is None:
        notes.extend(
            _replay_commands(
                run, catalog, behaviors, output, world, seed, drone, observer, watchers, injected
            )
        )
    else:
        world_name = world[1]
        config = SessionConfig(
            mission=script.path,
            catalog=catalog.name,
            seed=seed,
            world=None if world_name == "default" else world_name,
            record=output,
            drone=drone,
            behaviors=behaviors,
            injected=injected.faults,
            injected_metadata=injected.metadata,
            start=start,
            tap=tap,
            speed=speed,
        )
        with mission_prints_discarded():
            result = simulate(
                config,
                [observer, *watchers],
                catalog=catalog.catalog,
                script=script,
                catalog_text=catalog.text,
                world=world,
            )
        if result.outcome.ending.stopped:
            then = f"; then {', '.join(result.assurance)}" if result.assurance else ""
            notes.append(f"the replayed mission was stopped: {result.outcome.error}{then}")
        elif not result.outcome.returned:
            where = f" at {result.outcome.where}" if result.outcome.where else ""
            notes.append(f"the replayed mission raised{where}: {result.outcome.error}")
    outcome = builder.outcome(f"{run.outcome.source} (replay)", metadata=dict(metadata))
    return outcome, tuple(notes)


def _replay_commands(
    run: RecordedRun,
    catalog: ChosenCatalog,
    behaviors: BehaviorSet,
    output: str | Path | None,
    world: tuple[str, str],
    seed: int,
    drone: str,
    observer: OutcomeObserver,
    watchers: Sequence[BusObserver],
    injected: _Injected,
) -> list[str]:
    """Replay the recorded command stream in the simulator; notes about how."""
    world_model = with_failures(parse_world(*world), injected.faults)
    vehicle = SimVehicle(placed(world_model, injected.start), seed=seed)
    # The simulation starts when the recording does (a live log's clock need not be 0).
    offset = run.outcome.start_ns or 0
    observer.offset_ns = offset
    metadata = {
        "aeroexec_version": __version__,
        "seed": str(seed),
        "clock": "sim",
        "vehicle": vehicle.kind,
        "drone": drone,
        "catalog": catalog.name,
        "mission": "(mission/command stream)",
        "world": world[1],
        "replay_of": Path(run.outcome.source).name,
        "time_offset_ns": str(offset),
        **start_metadata(injected.start),
        **injected.metadata,
    }
    code = session_code(catalog.catalog, behaviors, allow_unimplemented=False)
    metadata.update(stand_in_metadata(code))
    attachments = {"catalog.yaml": catalog.text, "world.yaml": world[0], **code.attachments}
    _, observers, recorder = session_observers(
        output,
        drone,
        metadata,
        attachments,
        [observer, *watchers],
        code.records,
        vehicle.world,
        vehicle.state(),
        injected.tap,
    )
    notes: list[str] = []
    with recording_session(recorder, vehicle):
        executive = Executive(
            catalog.catalog,
            vehicle=vehicle,
            clock=paced(SimClock(), injected.speed),
            library=code.library,
            observers=observers,
            drone=drone,
        )
        start_observing(watchers, executive)
        player = CommandPlayer(executive, offset_ns=offset, wait_for_execute=True)
        stop = player.play(run.outcome.commands, until_ns=run.outcome.end_ns)
        mission_over(watchers, executive, stop is not None)
        ending, detail = "returned", "the recorded commands were replayed"
        if stop is not None:
            # As `run` ends a stopped mission: the action (a landing) in the simulator.
            home = vehicle.world.start
            done = carry_out(executive, MissionAPI(executive), vehicle, stop.action, home[:2])
            ending, detail = stop.by, stop.reason
            notes.append(stopped_note(stop, executive.now_s, done))
        end_observing(watchers, executive)
        if recorder is not None:
            end_recording(recorder, ending, detail, vehicle.state().fault)
    return notes


def stopped_note(stop: StopRequested, at_s: float, done: Sequence[str] = ()) -> str:
    """What a report says of a replay an observer stopped (a live viewer's abort)."""
    then = f"; then {', '.join(done)}" if done else ""
    return (
        f"stopped at {at_s:.1f} s ({stop.reason}): the recorded commands after it were not "
        f"replayed{then}"
    )
