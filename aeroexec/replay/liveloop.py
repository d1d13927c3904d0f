"""Closed-loop replay of a live flight: the recorded mission and the real behaviors again,
against the vehicle as it was recorded.

A live flight cannot be simulated again (the autopilot, its wind and its timing were
real), so where closed-loop replay of a simulated session re-simulates, this one plays
the recorded `vehicle/state` back (`ReplayVehicle`, refusing again the commands the
recorded vehicle refused: `aeroexec.replay.refusals`) and runs everything that decides on
it for real: the mission script (`mission.py`), the catalog's behaviors from the
standard library, the executive. With the recorded catalog and unchanged code every
behavior ends at the same tick, for the same reason, as in the flight.

Time: the replay's clock steps exactly where the flight's executive stepped
(`RecordedClock`: the log times of the recorded vehicle states, one per tick of the
live executive, after the state the flight started from, which `fly` records before its
first tick), so each tick sees the state the flight saw at that tick.

The flight's end: `aeroexec fly` recorded when and how the mission ended
(`mavlink/link` event `mission_end`). A mission stopped there by a signal or a lost
link is stopped at the same tick here; the commands the flight's ending issued after it
(inhibiting what was still active) are replayed at their recorded times.
"""

from __future__ import annotations

import json
from collections.abc import Generator, Iterator, Sequence
from pathlib import Path

from aeroexec import __version__
from aeroexec.executive.bus import BusObserver
from aeroexec.executive.clock import DEFAULT_TICK_NS, paced
from aeroexec.executive.executive import Executive
from aeroexec.mission.api import MissionAPI
from aeroexec.mission.script import MissionScript, run_script
from aeroexec.mission.session import (
    end_observing,
    mission_over,
    session_code,
    session_observers,
    stand_in_metadata,
    start_observing,
)
from aeroexec.plugins.discovery import BehaviorSet
from aeroexec.recording.tap import RecordTap
from aeroexec.replay.closedloop import (
    ChosenCatalog,
    mission_prints_discarded,
    script_to_run,
    stopped_note,
)
from aeroexec.replay.collect import STATE_TOPIC, OutcomeBuilder, OutcomeObserver, RecordedRun
from aeroexec.replay.outcome import RunOutcome
from aeroexec.replay.player import CommandPlayer
from aeroexec.replay.refusals import recorded_refusals
from aeroexec.replay.source import RecordingSource
from aeroexec.replay.vehicle import ReplayVehicle

LINK_TOPIC = "mavlink/link"


def is_live(run: RecordedRun) -> bool:
    """A recording of `aeroexec fly` (a MAVLink vehicle on the wall clock)."""
    return run.metadata.get("vehicle") == "mavlink"


class MissionStopped(BaseException):
    """The recorded mission was stopped here (a signal, a lost link): so is the replay.
    A `BaseException`, as what stopped the flight was: the mission cannot catch it."""


class RecordedClock:
    """Steps to the recorded tick times (ns, the recording's own time base), then on at
    `tick_ns` once they run out. With `stop_ns`, the step whose tick would come after
    it raises `MissionStopped` instead: the flight's mission never saw that tick."""

    kind = "replay"

    def __init__(
        self, ticks: Iterator[int], tick_ns: int = DEFAULT_TICK_NS, stop_ns: int | None = None
    ) -> None:
        self.tick_ns = tick_ns
        self.stop_ns = stop_ns
        self._ticks = ticks
        self._now = 0
        self._next: int | None = self._pull()

    def _pull(self) -> int | None:
        # The executive's first step is a tick after its start: a state recorded before
        # that is the one it started from, not a step.
        first = max(self._now + 1, self.tick_ns)
        for tick in self._ticks:
            if tick >= first:
                return tick
        return None

    def now_ns(self) -> int:
        return self._now

    def upcoming_ns(self) -> int:
        """When the next step will be: a recorded command goes in before it, as in flight."""
        return self._next if self._next is not None else self._now + self.tick_ns

    def advance(self) -> int:
        upcoming = self.upcoming_ns()
        if self.stop_ns is not None and upcoming > self.stop_ns:
            self.stop_ns = None  # once: what follows (the ending) steps on
            raise MissionStopped
        self._now = upcoming
        if self._next is not None:
            self._next = self._pull()
        return self._now


def _mission_end(path: str | Path) -> tuple[int, str] | None:
    """(log time, how) of the flight's `mission_end` event, if it recorded one."""
    for message in RecordingSource(path).scan(lambda name: name == LINK_TOPIC):
        try:
            data = json.loads(message.data)
        except ValueError:
            continue
        if isinstance(data, dict) and data.get("event") == "mission_end":
            return message.log_time_ns, str(data.get("how", ""))
    return None


def _ticks(path: str | Path) -> Generator[int, None, None]:
    for message in RecordingSource(path).scan(lambda name: name == STATE_TOPIC):
        yield message.log_time_ns


def replay_live(
    path: str | Path,
    run: RecordedRun,
    catalog: ChosenCatalog,
    behaviors: BehaviorSet,
    output: str | Path | None,
    horizon_ns: int | None,
    *,
    mission: MissionScript | None = None,
    trust_recording: bool = False,
    watchers: Sequence[BusObserver] = (),
    tap: RecordTap | None = None,
    speed: float | None = None,
) -> tuple[RunOutcome, tuple[str, ...]]:
    """Replay the live flight `run` (read from `path`) closed loop; outcome and notes.

    The mission that runs is chosen as for a simulated recording (`script_to_run`): the
    user's copy, the recorded one only when trusted, else the recorded command stream.
    `watchers` observe the replay's bus and session (a live view: a viewer's abort stops
    the replay at that tick; the recorded vehicle takes no ending); `tap` sees its
    recording as it is written, `speed` paces the recorded ticks to the wall clock."""
    notes: list[str] = []
    recorded = run.outcome
    drone = run.metadata.get("drone") or "drone1"
    script = script_to_run(run, mission, trust_recording, notes)
    end = _mission_end(path)
    stopped = end is not None and end[1] not in ("returned", "raised")
    ticks = _ticks(path)
    states = RecordingSource(path).scan(lambda name: name == STATE_TOPIC)
    # Without a script the recorded commands include the ending's: nothing to stop.
    stop = end[0] if end is not None and stopped and script is not None else None
    clock = RecordedClock(ticks, stop_ns=stop)
    # The recorded vehicle's refusals (arming refused, a command while the link was
    # lost) are its answers too: the replayed one gives them again.
    vehicle = ReplayVehicle(
        states,
        clock,
        refusals=recorded_refusals(path),
        upcoming=clock.upcoming_ns,
        heartbeat_timeout=run.metadata.get("heartbeat_timeout_s"),
    )
    builder = OutcomeBuilder(horizon_ns)
    metadata = {
        "aeroexec_version": __version__,
        "clock": "replay",
        "vehicle": vehicle.kind,
        "drone": drone,
        "catalog": catalog.name,
        "mission": run.metadata.get("mission") or "mission.py",
        "replay_of": Path(recorded.source).name,
        "replay_mode": "closed",
    }
    code = session_code(catalog.catalog, behaviors, allow_unimplemented=False)
    metadata.update(stand_in_metadata(code))
    attachments = {"catalog.yaml": catalog.text, **code.attachments}
    if script is not None:
        attachments["mission.py"] = script.text
    _, observers, recorder = session_observers(
        output,
        drone,
        metadata,
        attachments,
        [OutcomeObserver(builder), *watchers],
        code.records,
        start=vehicle.state(),
        tap=tap,
    )
    try:
        executive = Executive(
            catalog.catalog,
            vehicle=vehicle,
            clock=paced(clock, speed),
            library=code.library,
            observers=observers,
            drone=drone,
        )
        # The state the flight started from, as fly records it: a mission that never
        # stepped (its first command refused at once) ends in it.
        executive.publish_vehicle_state()
        start_observing(watchers, executive)
        stop = None
        if script is None:
            # The recorded vehicle moves on the recorded clock: the commands go at their
            # recorded times, not when the previous one ends here.
            player = CommandPlayer(executive)
            stop = player.play(recorded.commands, until_ns=recorded.end_ns)
        else:
            with mission_prints_discarded():
                try:
                    result = run_script(script, MissionAPI(executive))
                    if result.ending.stopped:
                        notes.append(f"the replayed mission was stopped: {result.error}")
                    elif not result.returned:
                        notes.append(f"the replayed mission raised: {result.error}")
                except MissionStopped:
                    how = end[1] if end is not None else ""
                    notes.append(f"stopped where the flight's mission was stopped ({how})")
            if executive.stop_request is None:
                # What the flight's ending did after the mission, at its recorded times.
                after = [c for c in recorded.commands if end is not None and c.time_ns >= end[0]]
                CommandPlayer(executive).play(after, until_ns=recorded.end_ns)
        mission_over(watchers, executive, executive.stop_request is not None)
        if stop is not None:
            notes.append(stopped_note(stop, executive.now_s))
        end_observing(watchers, executive)
    finally:
        ticks.close()
        states.close()
        if recorder is not None:
            recorder.close()
    outcome = builder.outcome(f"{recorded.source} (replay)", metadata=dict(run.metadata))
    return outcome, tuple(notes)
