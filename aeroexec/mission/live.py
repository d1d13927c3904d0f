"""A live session: catalog + MAVLink autopilot + mission script -> outcome (+ recording).

`fly()` is what `aeroexec fly` does: the live counterpart of `session.simulate()`. The
same executive core and behavior library run on the wall clock (`WallClock`, started
when the link is up: time 0 is the first moment the executive could act) against a
`MavlinkVehicle`; every MAVLink packet exchanged is published on the executive's bus
(`mavlink/tx`, `mavlink/rx`, plus `mavlink/rejected` and `mavlink/link`), so the
recorder writes it beside the executive's own channels.

Vehicle faults: a lost link or a mode the pilot (or the autopilot's own failsafe)
switched to ends the running motion behaviors at once with `PROCESS_FAILURE`
("vehicle fault: link_lost"): the behavior base class does it for every behavior that
lists those faults in `fails_on_faults` (all motion behaviors and LAND).

Endings: however the mission ends (returned, raised, SIGINT/SIGTERM/SIGHUP, a link lost
longer than `link_timeout`), `aeroexec.mission.ending.end_flight` brings the vehicle to
the `on_exit` policy before the link is closed and the recording gets its footer.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

from aeroexec import __version__
from aeroexec.catalog.loader import load_catalog
from aeroexec.catalog.model import Catalog
from aeroexec.catalog.paths import DEFAULT_CATALOG
from aeroexec.executive.bus import BusObserver
from aeroexec.executive.clock import WallClock
from aeroexec.executive.executive import Executive
from aeroexec.interrupts import Interrupted
from aeroexec.mission.activity import Activation
from aeroexec.mission.api import MissionAPI
from aeroexec.mission.ending import ON_EXIT, Ending, OnExit, end_flight
from aeroexec.mission.script import MissionOutcome, MissionScript, load_mission, run_script
from aeroexec.mission.session import (
    SessionResult,
    end_observing,
    mission_over,
    session_code,
    session_observers,
    stand_in_metadata,
    start_observing,
)
from aeroexec.plugins.discovery import BehaviorSet
from aeroexec.recording.tap import RecordTap
from aeroexec.vehicles.base import VehicleCommandError
from aeroexec.vehicles.mavlink.codec import signing_key
from aeroexec.vehicles.mavlink.endpoint import (
    DEFAULT_BAUD,
    DEFAULT_GCS_URL,
    MavlinkError,
    parse_endpoint,
)
from aeroexec.vehicles.mavlink.preflight import GcsFailsafeOff, preflight
from aeroexec.vehicles.mavlink.vehicle import (
    FAILSAFES,
    Failsafe,
    LinkTimeout,
    MavlinkConfig,
    MavlinkVehicle,
)


@dataclass(frozen=True)
class FlightConfig:
    mission: str | Path
    connect: str = DEFAULT_GCS_URL
    catalog: str | Path = DEFAULT_CATALOG
    record: str | Path | None = None
    drone: str = "drone1"
    heartbeat_timeout: float = 3.0
    #: What to do when a lost link comes back: land, hold or rtl.
    failsafe: Failsafe = "land"
    #: How the flight ends when the mission is over: land, hold or none.
    on_exit: OnExit = "land"
    #: A link lost this long (s) ends the mission; the ending waits that long for it too.
    link_timeout: float = 30.0
    #: `--signing-key`: 64 hex digits, or a passphrase (hashed with SHA-256).
    signing_key: str | None = None
    allow_remote: bool = False
    connect_timeout: float = 10.0
    ack_timeout: float = 1.0
    retries: int = 2
    #: The behaviors to fly with (default: the standard library).
    behaviors: BehaviorSet | None = None
    #: Fly catalog behaviors without an implementation as announced stand-ins.
    allow_unimplemented: bool = False
    #: Serial devices given without `,BAUD`.
    baud: int = DEFAULT_BAUD
    #: Fly although the autopilot's GCS failsafe is off (one warning instead of a refusal).
    allow_no_gcs_failsafe: bool = False
    #: Sees the recording as it is written (a live view); recorded even without `record`.
    tap: RecordTap | None = None

    def vehicle_config(self) -> MavlinkConfig:
        """The vehicle's configuration; `MavlinkError` for values that cannot work."""
        key = None
        if self.signing_key is not None:
            try:
                key = signing_key(self.signing_key)
            except ValueError as exc:
                raise MavlinkError(f"--signing-key: {exc}") from None
        if self.failsafe not in FAILSAFES:
            raise MavlinkError(f"--failsafe must be one of {', '.join(FAILSAFES)}")
        if self.on_exit not in ON_EXIT:
            raise MavlinkError(f"--on-exit must be one of {', '.join(ON_EXIT)}")
        try:
            return MavlinkConfig(
                url=self.connect,
                allow_remote=self.allow_remote,
                signing_key=key,
                heartbeat_timeout=self.heartbeat_timeout,
                failsafe=self.failsafe,
                link_timeout=self.link_timeout,
                baud=self.baud,
                connect_timeout=self.connect_timeout,
                ack_timeout=self.ack_timeout,
                retries=self.retries,
            )
        except ValueError as exc:
            raise MavlinkError(str(exc)) from None


@dataclass(frozen=True)
class FlightResult(SessionResult):
    #: How the flight ended (see `aeroexec.mission.ending`).
    ending: Ending | None = None
    link_losses: int = 0

    @property
    def safe(self) -> bool:
        """The vehicle ended landed and disarmed, every step of the ending seen, and the
        link never dropped."""
        return self.ending is not None and self.ending.confirmed and self.link_losses == 0

    def mission_failures(self) -> tuple[Activation, ...]:
        """The activations that ended PROCESS_FAILURE: the behavior could not do what the
        mission asked because the autopilot refused a command (or never acknowledged it),
        the vehicle had a fault (link lost, a mode it was switched to), or the behavior's
        own code failed. On a real aircraft that is a mission that failed, whatever the
        script did with the result: `aeroexec fly` exits 1. Other endings (WRONG_PROGRESS,
        TIMEOUT_REACHED, INTERRUPTED, a rejected activation) are results the mission
        judges for itself, as in simulation."""
        return tuple(a for a in self.activations if a.end_code == "PROCESS_FAILURE")

    def problem(self) -> str:
        """Why the flight is not `safe`, in one line ("" when it is)."""
        if self.safe or self.ending is None:
            return ""
        if self.ending.confirmed:
            losses = self.link_losses
            return (
                f"the link was lost {losses} time{'s' if losses > 1 else ''} during the "
                f"flight; vehicle {self.ending.last_seen}"
            )
        return self.ending.line()


def fly(
    config: FlightConfig,
    observers: Iterable[BusObserver] = (),
    *,
    catalog: Catalog | None = None,
    script: MissionScript | None = None,
    catalog_text: str | None = None,
    on_listening: Callable[[MavlinkVehicle], None] | None = None,
    on_connected: Callable[[MavlinkVehicle], None] | None = None,
    on_preflight: Callable[[str], None] | None = None,
    announce: Callable[[str], None] | None = None,
) -> FlightResult:
    """Fly one mission on a live autopilot. Unreadable inputs (mission, catalog, URL,
    key) and catalog behaviors without an implementation raise `AeroexecError`s before
    the link opens; no heartbeat raises `MavlinkError` before any recording file is
    created. `announce` is told each stand-in once, before the link opens. After the
    connection, `preflight` reads the autopilot's failsafes (each line to
    `on_preflight`): with its GCS failsafe off, `GcsFailsafeOff` before anything is
    armed or recorded, unless `allow_no_gcs_failsafe` (then one warning to `announce`). A signal
    (`Interrupted`) is re-raised after the ending, with what was done in its notes."""
    observers = list(observers)
    catalog = catalog if catalog is not None else load_catalog(config.catalog)
    script = script if script is not None else load_mission(config.mission)
    code = session_code(catalog, config.behaviors, config.allow_unimplemented, announce)
    vehicle_config = config.vehicle_config()
    parse_endpoint(config.connect, allow_remote=config.allow_remote, baud=config.baud)
    vehicle = MavlinkVehicle(vehicle_config)
    recorder = None
    stopped: BaseException | None = None
    try:
        if on_listening is not None:
            on_listening(vehicle)
        try:
            vehicle.connect()
        except Interrupted as exc:
            exc.notes.append("stopped before the autopilot was ready; nothing was commanded")
            raise
        if on_connected is not None:
            on_connected(vehicle)
        checked = preflight(vehicle)
        for line in checked.lines:
            if on_preflight is not None:
                on_preflight(line)
        if checked.gcs_failsafe_off:
            if not config.allow_no_gcs_failsafe:
                raise GcsFailsafeOff(
                    f"{checked.gcs_failsafe_off}, or pass --allow-no-gcs-failsafe; "
                    "nothing was armed"
                )
            if announce is not None:
                announce(f"warning: {checked.gcs_failsafe_off} (--allow-no-gcs-failsafe)")
        clock = WallClock()  # time 0: the link is up (not when we began to wait for it)
        metadata = {
            "aeroexec_version": __version__,
            "clock": clock.kind,
            "vehicle": vehicle.kind,
            "drone": config.drone,
            "catalog": Path(str(config.catalog)).name,
            "mission": Path(script.path).name,
            "connect": vehicle.endpoint.url,
            "autopilot_system": str(vehicle.target[0] if vehicle.target else ""),
            "signing": "yes" if vehicle_config.signing_key is not None else "no",
            "failsafe": config.failsafe,
            "on_exit": config.on_exit,
            "heartbeat_timeout_s": f"{config.heartbeat_timeout:g}",
            "link_timeout_s": f"{config.link_timeout:g}",
            "failsafe_parameters": checked.metadata(),
            **stand_in_metadata(code),
        }
        activity, all_observers, recorder = session_observers(
            config.record,
            config.drone,
            metadata,
            {
                "catalog.yaml": catalog_text if catalog_text is not None else catalog.text,
                "mission.py": script.text,
                **code.attachments,
            },
            observers,
            code.records,
            start=vehicle.state(),
            live=clock.kind == "wall",
            tap=config.tap,
        )
        executive = Executive(
            catalog,
            vehicle=vehicle,
            clock=clock,
            library=code.library,
            observers=all_observers,
            drone=config.drone,
        )
        vehicle.tap = executive.bus.publish  # hands over the traffic of the connection too
        executive.publish_vehicle_state()  # what the mission starts from (replay needs it)
        start_observing(observers, executive)
        api = MissionAPI(executive)
        outcome = MissionOutcome(False, None, "the mission did not end")
        try:
            # A mission that never lets go of a signal is not ended by exiting: the
            # vehicle must get its ending (it is raised again at every safe point).
            outcome = run_script(script, api, forced_exit=False)
            # A mission stopped from outside says by whom ("property", "abort"): a
            # replay stops it at the same tick, as for a signal.
            how = (
                outcome.ending.value
                if outcome.ending.stopped
                else "returned"
                if outcome.returned
                else "raised"
            )
        except LinkTimeout as exc:
            outcome = MissionOutcome(
                False, None, f"stopped: the link was lost for {exc.silent_s:.1f} s"
            )
            how = "link_timeout"
        except BaseException as exc:
            # A signal, Ctrl-C, an unusable script, our own bug: whatever it is, the
            # vehicle gets its ending before the exception goes on.
            stopped = exc
            how = exc.name if isinstance(exc, Interrupted) else type(exc).__name__
        mission_over(observers, executive, outcome.ending.stopped)
        # When and how the mission ended: replay stops a mission stopped here at the
        # same tick, and tells the ending's commands from the mission's.
        executive.bus.publish(
            "mavlink/link", {"event": "mission_end", "url": vehicle.endpoint.url, "how": how}
        )
        on_exit = config.on_exit
        if outcome.ending.stopped and executive.stop_request is not None:
            # A violated property's action (`fly --spec`) decides how the flight ends.
            action = executive.stop_request[1]
            executive.stop_request = None  # honoured: the ending steps on
            if action == "rtl":
                with contextlib.suppress(VehicleCommandError):
                    executive.log(f"property action rtl: {vehicle.return_home()}", "WARNING")
                on_exit = "land"  # then wait, as for a landing, for it to be down
            elif action in ("land", "hold"):
                on_exit = action  # type: ignore[assignment]
        ending = end_flight(executive, api, vehicle, on_exit, link_timeout=config.link_timeout)
        with contextlib.suppress(LinkTimeout):
            vehicle.step(0.0)  # what arrived since the last tick is recorded too
        executive.bus.publish(
            "mavlink/link",
            {
                "event": "ending",
                "url": vehicle.endpoint.url,
                "down": ending.down,
                "last_seen": ending.last_seen,
                "actions": list(ending.actions),
                "problem": ending.problem,
            },
        )
        executive.bus.publish("mavlink/stats", lambda: _stats(vehicle))
        end_observing(observers, executive)
    finally:
        if recorder is not None:
            recorder.close()
        vehicle.close()
    if stopped is not None:
        if isinstance(stopped, Interrupted):
            stopped.notes.append(ending.line())
            if config.record is not None:
                stopped.notes.append(f"recording finalized: {config.record}")
        raise stopped
    losses = vehicle.link_losses
    link_summary = vehicle.stats.summary()
    if losses:
        link_summary += f"; link lost {losses} time{'s' if losses > 1 else ''}"
    return FlightResult(
        outcome=outcome,
        activations=tuple(activity.rows),
        duration_s=executive.now_s,
        final_state=vehicle.state(),
        recording=str(config.record) if config.record is not None else None,
        # The recorded metadata plus, after the fact, what went over the link.
        metadata={**metadata, "link_summary": link_summary},
        ending=ending,
        link_losses=losses,
    )


def _stats(vehicle: MavlinkVehicle) -> dict[str, object]:
    stats = vehicle.stats.as_dict()
    stats.pop("tail", None)
    return {**stats, "link_losses": vehicle.link_losses}
