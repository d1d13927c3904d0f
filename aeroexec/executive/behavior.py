"""The `Behavior` base class (the thesis' Behavior Process).

A behavior author subclasses `Behavior`, sets `name` to the catalog name it implements,
and fills four hooks:

    class Hover(Behavior):
        name = "KEEP_HOVERING"

        def check_situation(self, beliefs):
            return Situation.ok_if(beliefs.holds("flying(self)"), "not flying")

        def on_start(self, args):
            self.duration = args.get("DURATION", 5)
            self.vehicle.hover()

        def on_run(self):
            if self.elapsed >= self.duration:
                return Finished()

The base class does the rest: it asks the resource manager for the behavior's
capabilities before `on_start` and releases them after `on_stop`, arms the catalog
timeout (`TIME_OUT`), publishes exactly one `behavior_event` per activation, stops
itself after it, and turns any exception in a hook into a `PROCESS_FAILURE` event.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING, Any, ClassVar

from aeroexec.executive.clock import NS_PER_S
from aeroexec.executive.messages import OK, BehaviorEvent, EventCode, ServiceResult, failure
from aeroexec.executive.process import DroneProcess

if TYPE_CHECKING:
    from aeroexec.catalog.model import BehaviorDescriptor
    from aeroexec.executive.beliefs import Beliefs
    from aeroexec.executive.executive import Executive
    from aeroexec.vehicles.base import Vehicle


@dataclass(frozen=True, slots=True)
class Situation:
    """The answer of `check_situation`: may the behavior start now, and if not, why."""

    ok: bool
    reason: str = ""

    @classmethod
    def ok_if(cls, condition: bool, reason: str) -> Situation:
        return cls(True) if condition else cls(False, reason)


ALLOWED = Situation(True)


class FlightState(str, Enum):
    """A behavior's declared situation (see `Behavior.needs` and `Behavior.leaves`)."""

    LANDED = "landed"
    FLYING = "flying"


@dataclass(frozen=True, slots=True)
class Finished:
    """Returned by `on_run` when the behavior is done."""

    code: EventCode = EventCode.GOAL_ACHIEVED
    detail: str = ""


def _describe(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}"


class Behavior:
    """Base class of every behavior. Authors override only the four hooks below."""

    #: The catalog name this class implements (e.g. "GO_TO_POINT").
    name: ClassVar[str] = ""
    #: Vehicle faults (prefixes of `VehicleState.fault`) that make this behavior's goal
    #: impossible: they end it at once with PROCESS_FAILURE "vehicle fault: <fault>" (a
    #: behavior that commands motion cannot go on over a lost link or an empty battery).
    #: Faults the behavior judges itself (a stuck motor stops progress: WRONG_PROGRESS)
    #: are not listed; any ending but success names the vehicle's fault all the same.
    fails_on_faults: ClassVar[tuple[str, ...]] = ()
    #: The argument names `on_start` reads, as the behavior spells them; None: not
    #: declared. Declared names are matched to the catalog's regardless of case (a
    #: catalog's `coordinates` reaches a behavior that reads `COORDINATES`), and the
    #: verifier checks them against the catalog (a catalog argument no code reads).
    argument_names: ClassVar[tuple[str, ...] | None] = None
    #: Declared situation, a static summary of `check_situation` (read by the offline
    #: verifier, which runs missions abstractly): the flight state the behavior needs
    #: to start (None: either), and the one it leaves when it achieves its goal (None:
    #: unchanged). `check_situation` stays the authority when the behavior runs.
    needs: ClassVar[FlightState | None] = None
    leaves: ClassVar[FlightState | None] = None

    # -- the author's hooks ------------------------------------------------------------
    def check_situation(self, beliefs: Beliefs) -> Situation:
        """May the behavior start in the current situation? Default: yes."""
        return ALLOWED

    def on_start(self, args: Mapping[str, Any]) -> None:
        """Start doing the job; `args` are validated, keyed by the names declared in
        `argument_names` (else by the catalog's spelling)."""

    def on_run(self) -> Finished | None:
        """Called every tick while running; return `Finished(...)` when done."""
        return None

    def on_stop(self) -> None:
        """Undo what `on_start` set going (called once, however the behavior ends)."""

    # -- what authors may use ------------------------------------------------------------
    @property
    def vehicle(self) -> Vehicle:
        return self._host.vehicle

    @property
    def beliefs(self) -> Beliefs:
        return self._host.beliefs

    @property
    def now(self) -> float:
        """Seconds since the session started."""
        return self._host.clock.now_ns() / NS_PER_S

    @property
    def elapsed(self) -> float:
        """Seconds since this activation started."""
        return (self._host.clock.now_ns() - self._started_ns) / NS_PER_S

    @property
    def arguments(self) -> Mapping[str, Any]:
        return self._arguments

    def log(self, message: str, level: str = "INFO") -> None:
        self._host.log(f"{self.behavior_name}: {message}", level, name=self.behavior_name)

    # -- the machinery (not for authors) -------------------------------------------------
    def bind(self, host: Executive, descriptor: BehaviorDescriptor) -> None:
        """Attach to an executive; called once when the executive is built."""
        self._host = host
        self.descriptor = descriptor
        self.behavior_name = descriptor.name
        self.process = DroneProcess(f"behavior_{descriptor.name.lower()}")
        self.process.set_up()
        self.uid = 0
        self._arguments: Mapping[str, Any] = {}
        self._started_ns = 0
        self._deadline_ns: int | None = None

    @property
    def running(self) -> bool:
        return self.process.running

    def situation(self) -> ServiceResult:
        """The `check_situation` service: the author's answer, exceptions included."""
        try:
            verdict = self.check_situation(self._host.beliefs)
        except Exception as exc:  # an author bug must not escape into the core
            return failure(f"{self.behavior_name}: check_situation failed: {_describe(exc)}")
        if not isinstance(verdict, Situation):  # so is a wrong return type
            return failure(
                f"{self.behavior_name}: check_situation returned "
                f"{type(verdict).__name__}, not a Situation"
            )
        if verdict.ok:
            return OK
        return failure(f"{self.behavior_name}: {verdict.reason}")

    def start(self, uid: int, arguments: Mapping[str, Any], timeout: float | None) -> ServiceResult:
        """The `start` service (Algorithm 3.2): capabilities, timeout, then `on_start`.

        An exception in `on_start` does not undo the activation: the behavior ends at
        once with `PROCESS_FAILURE`, so the mission sees one event for it like any other.
        """
        resources = self._host.resources.activate_resources(self.behavior_name)
        if not resources.ok:
            return resources
        started = self.process.start()
        if not started.ok:
            self._host.resources.cancel_resources(self.behavior_name)
            return started
        self.uid = uid
        self._arguments = self._spelled(arguments)
        self._started_ns = self._host.clock.now_ns()
        self._deadline_ns = (
            None
            if timeout is None or self.descriptor.recurrent
            else self._started_ns + round(timeout * NS_PER_S)
        )
        try:
            self.on_start(self._arguments)
        except Exception as exc:
            self.finish(EventCode.PROCESS_FAILURE, f"on_start failed: {_describe(exc)}")
        return OK

    def _spelled(self, arguments: Mapping[str, Any]) -> dict[str, Any]:
        """The arguments keyed as the behavior declares them (case-insensitive match)."""
        declared = self.argument_names
        if not declared:
            return dict(arguments)
        spelling = {name.casefold(): name for name in declared}
        return {spelling.get(key.casefold(), key): value for key, value in arguments.items()}

    def tick(self) -> None:
        """One run() of Algorithm 3.3: supervise, and end with one event when finished."""
        if not self.process.running:
            return
        if self.fails_on_faults:
            fault = self._host.vehicle.state().fault
            if fault and fault.startswith(self.fails_on_faults):
                self.finish(EventCode.PROCESS_FAILURE, f"vehicle fault: {fault}")
                return
        try:
            outcome = self.on_run()
        except Exception as exc:
            self.finish(EventCode.PROCESS_FAILURE, f"on_run failed: {_describe(exc)}")
            return
        if outcome is not None:
            self._finish_with(outcome)
        elif self._deadline_ns is not None and self._host.clock.now_ns() >= self._deadline_ns:
            self.finish(EventCode.TIME_OUT, f"no result within {self.descriptor.timeout:g} s")

    def _finish_with(self, outcome: object) -> None:
        """End with what on_run returned; a wrong type or an unknown code is an author
        bug, reported as PROCESS_FAILURE rather than raised into the core."""
        if not isinstance(outcome, Finished):
            kind = type(outcome).__name__
            self.finish(EventCode.PROCESS_FAILURE, f"on_run returned {kind}, not Finished")
            return
        try:
            code = EventCode(outcome.code)
        except (ValueError, TypeError):
            self.finish(
                EventCode.PROCESS_FAILURE, f"on_run finished with unknown code {outcome.code!r}"
            )
            return
        self.finish(code, str(outcome.detail))

    def finish(self, code: EventCode, detail: str = "") -> BehaviorEvent | None:
        """Stop (Algorithm 3.4) and publish the activation's one event. Idempotent."""
        if not self.process.running:
            return None
        try:
            self.on_stop()
        except Exception as exc:
            if code is not EventCode.PROCESS_FAILURE:
                code, detail = EventCode.PROCESS_FAILURE, f"on_stop failed: {_describe(exc)}"
        self.process.stop()
        self._host.resources.cancel_resources(self.behavior_name)
        if code is not EventCode.GOAL_ACHIEVED and code is not EventCode.INTERRUPTED:
            detail = self._with_fault(detail)
        event = BehaviorEvent(self.behavior_name, self.uid, code, self._host.clock.now_ns(), detail)
        self._host.on_behavior_event(event)
        return event

    def _with_fault(self, detail: str) -> str:
        """`detail`, naming the vehicle's fault if it has one: a behavior that failed
        while the vehicle was failing says so, whatever its own measure caught."""
        try:
            fault = self._host.vehicle.state().fault
        except Exception:  # a vehicle that cannot say: the event goes out anyway
            return detail
        if not fault or fault in detail:
            return detail
        return f"{detail}; vehicle fault: {fault}" if detail else f"vehicle fault: {fault}"


class GenericBehavior(Behavior):
    """Stands in for a catalog behavior the library does not implement.

    Goal-based ones succeed after `duration` seconds; recurrent ones run until
    inhibited. Lets any catalog be exercised (verifier witnesses, generated catalogs).
    """

    duration = 1.0

    def on_run(self) -> Finished | None:
        if not self.descriptor.recurrent and self.elapsed >= self.duration:
            return Finished(EventCode.GOAL_ACHIEVED, "generic behavior (no implementation)")
        return None
