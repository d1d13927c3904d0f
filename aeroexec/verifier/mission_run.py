"""AX709-AX715: a mission checked as a sequence, by running it abstractly.

The folded mission (`mission_fold`) is run path by path against the real executive —
`Executive` with its behavior coordinator, specialist and resource manager — on
stand-in behaviors and a vehicle that only knows whether it flies (`stand_ins`). What
the executive answers is the verdict: an activation its coordinator rejects, a behavior
it preempts, what is still active. The checks:

* AX709 an inhibit of a behavior an earlier activation preempted (rejected: not active);
* AX710 an activation the resource manager rejects because a capability conflicts with
  one a still-active behavior holds;
* AX711 a behavior started in a flight state it does not accept (a motion behavior
  before any take-off), as the behaviors declare it;
* AX712 recurrent behaviors still running when the mission ends;
* AX713 LAND (a behavior that leaves the vehicle landed) while an active behavior
  still needs it flying;
* AX714 a literal target too far for the behavior's timeout at the vehicle's limits
  (from the world description), from where the vehicle is on that path;
* AX715 the exploration reached its bounds (reported, so silence is not taken as proof).

Paths: a branch the folder could not decide is explored both ways; states that reach
the same point with the same executive state (active behaviors, flight state, what was
preempted) are merged, keeping the shortest path, at most `MAX_STATES` per point. A loop
runs until no new state reaches its head (a fixed point), at most `MAX_ITERATIONS`
times. An activated behavior is assumed still running at every later call (it may be);
an executed one ends with GOAL_ACHIEVED before the next call. Each finding carries the
path that leads to it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from aeroexec import interrupts
from aeroexec.behaviors import STANDARD_LIBRARY
from aeroexec.catalog.model import Catalog, Severity
from aeroexec.errors import Mark
from aeroexec.executive.behavior import Behavior, FlightState
from aeroexec.executive.executive import Executive
from aeroexec.executive.messages import ServiceResult
from aeroexec.vehicles.base import Vec3
from aeroexec.vehicles.world import World, default_world
from aeroexec.verifier.findings import Finding, PathStep, Related
from aeroexec.verifier.mission_fold import (
    Branch,
    CallNode,
    Flow,
    FoldedMission,
    Inline,
    Jump,
    Loop,
    MissionCall,
    Try,
    Unrolled,
    is_known,
)
from aeroexec.verifier.reach import describe_limits, travel_between
from aeroexec.verifier.registry import mission_rule
from aeroexec.verifier.stand_ins import NOT_FLYING, NOT_LANDED, FlightStateVehicle, stand_ins

E, W, INFO = Severity.ERROR, Severity.WARNING, Severity.INFO

MAX_STATES = 32  # distinct executive states kept at one point of the mission
MAX_ITERATIONS = 8  # runs of a loop's body before its fixed point is given up
MAX_SENDS = 5_000  # calls sent to executives for one mission (replays included)
EXECUTE_WAIT_S = 10.0  # clock seconds a stand-in gets to end (it ends at the next tick)
SHOWN_STEPS = 8

INHIBIT_PREEMPTED = mission_rule(
    "AX709",
    "mission-inhibit-preempted",
    W,
    """A mission inhibits a behavior that an earlier activation on the same path already
    preempted (it is in one of the later behavior's incompatible lists). In flight: the
    inhibition is rejected ('not active'); the mission's author believed the behavior
    still ran until then, so whatever it was for stopped earlier than planned. The
    finding names the preempting call and the path. Fix: drop the inhibit, or activate
    the behavior again where it is still needed.""",
).code
CAPABILITY_CONFLICT = mission_rule(
    "AX710",
    "mission-capability-conflict",
    E,
    """On some path, an activation is rejected by the resource manager: one of the
    behavior's capabilities conflicts with a capability a behavior activated earlier
    still holds (the two are not declared incompatible, so nothing preempts the first).
    In flight: the call fails and the mission goes on without the behavior. Fix:
    inhibit the first behavior before, or declare the two incompatible (a shared
    list).""",
).code
WRONG_FLIGHT_STATE = mission_rule(
    "AX711",
    "mission-wrong-flight-state",
    E,
    """On some path, a behavior is started in a flight state it does not accept, as
    its implementation declares it (`Behavior.needs`): a motion behavior before any
    TAKE_OFF, or after LAND; TAKE_OFF while already flying. In flight: its situation
    check rejects the activation. Fix: take off first (or land first), or move the call
    to where the vehicle is in the right state.""",
).code
RECURRENT_LEFT_RUNNING = mission_rule(
    "AX712",
    "mission-recurrent-left-running",
    W,
    """On some path, a recurrent behavior the mission activated is still running when
    the mission ends (recurrent behaviors never end by themselves). In flight: it keeps
    its capabilities and processes after the mission, until someone inhibits it. Fix:
    inhibit it before the mission returns, on every path.""",
).code
LAND_WHILE_NEEDED = mission_rule(
    "AX713",
    "mission-land-while-needed",
    W,
    """On some path, LAND (a behavior that leaves the vehicle landed) starts while an
    active behavior still needs the vehicle flying (it is not preempted by LAND). In
    flight: that behavior keeps commanding a vehicle that is landing, then fails or
    times out on the ground. Fix: inhibit it before landing, or make LAND preempt it
    (put it in a list LAND names).""",
).code
TARGET_TOO_FAR = mission_rule(
    "AX714",
    "mission-target-too-far",
    W,
    """On some path, a behavior is sent to a literal target it cannot reach within its
    timeout: the distance from where the vehicle is on that path (the world's start,
    the take-off height, earlier targets), at the vehicle's speed and acceleration
    limits from the world description, takes longer. In flight: it ends in TIME_OUT.
    Fix: split the flight, or raise the behavior's timeout.""",
).code
BOUNDED = mission_rule(
    "AX715",
    "mission-analysis-bounded",
    INFO,
    """The abstract run of a mission reached one of its bounds (distinct states at one
    point, loop iterations, calls sent, constant loops unrolled: nested ones beyond 1,000
    iterations in all stay loops), so some paths were not followed to the end. In
    flight: nothing; the sequence checks (AX709-AX714) are complete only up to the bound.
    Fix: nothing needed; a smaller mission function, or fewer undecidable branches,
    lets the verifier follow every path.""",
).code


@dataclass(eq=False)
class _State:
    """One way through the mission so far: what was sent, and what it did."""

    actions: tuple[MissionCall, ...] = ()
    steps: tuple[PathStep, ...] = ()
    #: behavior -> the step that activated it (while it is thought to run).
    origin: dict[str, PathStep] = field(default_factory=dict)
    #: behavior -> (its preemptor, the step of the preempting call).
    preempted: dict[str, tuple[str, PathStep]] = field(default_factory=dict)
    flight_change: PathStep | None = None
    position: Vec3 | None = None
    raised: bool = False
    executive: Executive | None = None

    def fork(self) -> _State:
        return _State(
            self.actions,
            self.steps,
            dict(self.origin),
            dict(self.preempted),
            self.flight_change,
            self.position,
            self.raised,
        )

    def step(self, step: PathStep) -> None:
        self.steps = (*self.steps, step)


@dataclass
class _Ends:
    """Where the states leaving a piece of flow go."""

    normal: list[_State] = field(default_factory=list)
    breaks: list[_State] = field(default_factory=list)
    continues: list[_State] = field(default_factory=list)
    returns: list[_State] = field(default_factory=list)


def called_from(via: tuple[tuple[str, Mark], ...]) -> tuple[Related, ...]:
    """The helper calls leading to a mission call, innermost first, as notes."""
    return tuple(Related.called_from(name, mark) for name, mark in reversed(via))


def _path_text(steps: tuple[PathStep, ...]) -> str:
    shown = [s.describe() for s in steps[-SHOWN_STEPS:]]
    if len(steps) > SHOWN_STEPS:
        shown.insert(0, "...")
    return "; ".join(shown) if shown else "at the start"


class MissionRun:
    def __init__(
        self,
        catalog: Catalog,
        note: str = "",
        library: Mapping[str, type[Behavior]] | None = None,
        world: World | None = None,
    ) -> None:
        self.catalog = catalog
        self.note = note
        self.library = STANDARD_LIBRARY if library is None else library
        self.world = world or default_world()
        self.classes = stand_ins(tuple(catalog.behaviors), self.library)
        self.sends = 0
        self.bounds_hit: list[str] = []
        self.findings: dict[tuple[Any, ...], Finding] = {}
        self.file = ""
        #: The call being applied (its helper calls become the findings' notes).
        self.calling: MissionCall | None = None

    # -- executives ----------------------------------------------------------------------
    def executive(self, state: _State) -> Executive:
        if state.executive is None:
            executive = Executive(
                self.catalog,
                vehicle=FlightStateVehicle(self.world.start),
                library=self.classes,
            )
            for call in state.actions:
                self.send(executive, call)
            state.executive = executive
        return state.executive

    def send(self, executive: Executive, call: MissionCall) -> ServiceResult | None:
        """What the mission API would do with the call; None when it sends nothing."""
        interrupts.check()  # a safe point: a long abstract run stops on Ctrl-C
        self.sends += 1
        name = call.behavior
        descriptor = self.catalog.behaviors.get(name) if name is not None else None
        if name is None or descriptor is None:
            return None
        if call.kind == "inhibit":
            return executive.inhibit_behavior(name)
        if call.kind == "execute" and descriptor.recurrent:
            return None  # the API refuses it (AX705)
        arguments = {a.name: a.value for a in call.arguments if is_known(a.value)}
        result = executive.activate_behavior(name, arguments)
        if result.ok and call.kind == "execute":
            uid = result.payload["uid"]
            seen = len(executive.events)
            executive.behaviors[name].finishing = True  # type: ignore[attr-defined]
            executive.run_until(
                lambda: any(e.uid == uid for e in executive.events[seen:]), EXECUTE_WAIT_S
            )
            executive.step()  # the beliefs catch up with the flight state it left
        return result

    # -- findings ------------------------------------------------------------------------
    def report(
        self,
        rule: str,
        severity: Severity,
        message: str,
        at: PathStep,
        state: _State,
        *subjects: str,
    ) -> None:
        via = self.calling.via if self.calling is not None else ()
        finding = Finding.at(
            rule,
            severity,
            f"{message} (path: {_path_text(state.steps)}){self.note}",
            Mark(self.file, at.line, at.column),
            subjects,
            path=state.steps,
            related=called_from(via),
        )
        key = (rule, at.line, at.column, finding.subjects)
        known = self.findings.get(key)
        if known is None or len(finding.path) < len(known.path):
            self.findings[key] = finding

    # -- running -------------------------------------------------------------------------
    def run(self, mission: FoldedMission, file: str) -> list[Finding]:
        self.file = file
        self.bounds_hit.extend(mission.bounds)
        start = _State(position=self.world.start)
        ends = self.explore(mission.flow, [start])
        for state in [*ends.normal, *ends.returns, *ends.breaks, *ends.continues]:
            if not state.raised:
                self.at_end(state)
        findings = list(self.findings.values())
        if self.bounds_hit:
            findings.append(
                Finding.at(
                    BOUNDED,
                    INFO,
                    "the sequence checks followed the mission up to their bounds: "
                    + "; ".join(dict.fromkeys(self.bounds_hit))
                    + self.note,
                    Mark(file, 1, 1),
                    (file,),
                )
            )
        return findings

    def explore(self, flow: Flow, states: list[_State]) -> _Ends:
        ends = _Ends()
        current = states
        for node in flow:
            if not current:
                break
            if self.sends > MAX_SENDS:
                self.bounds_hit.append(f"{MAX_SENDS} calls sent to the executive")
                ends.normal.extend(current)
                return ends
            if isinstance(node, CallNode):
                for state in current:
                    self.apply(state, node.call)
                ends.returns.extend(s for s in current if s.raised)
                current = [s for s in current if not s.raised]
            elif isinstance(node, Branch):
                merged: list[_State] = []
                for state in current:
                    for index, (label, arm) in enumerate(node.arms):
                        taken = state if index == len(node.arms) - 1 else state.fork()
                        taken.step(PathStep(node.mark.line, node.mark.column, label))
                        sub = self.explore(arm, [taken])
                        merged.extend(sub.normal)
                        ends.breaks.extend(sub.breaks)
                        ends.continues.extend(sub.continues)
                        ends.returns.extend(sub.returns)
                current = self.merge(merged, f"line {node.mark.line}")
            elif isinstance(node, Loop):
                current = self.loop(node, current, ends)
            elif isinstance(node, Unrolled):
                current = self.unrolled(node, current, ends)
            elif isinstance(node, Try):
                current = self.try_block(node, current, ends)
            elif isinstance(node, Inline) and node.passthrough:
                sub = self.explore(node.body, current)
                ends.returns.extend(sub.returns)
                ends.breaks.extend(sub.breaks)
                ends.continues.extend(sub.continues)
                current = self.merge(sub.normal, f"line {node.mark.line}")
            elif isinstance(node, Inline):
                sub = self.explore(node.body, current)
                # A helper's return comes back here; a raise ends the mission.
                ends.returns.extend(s for s in sub.returns if s.raised)
                returned = [s for s in sub.returns if not s.raised]
                current = self.merge(
                    [*sub.normal, *returned, *sub.breaks, *sub.continues],
                    f"line {node.mark.line}",
                )
            elif isinstance(node, Jump):
                for state in current:
                    state.step(PathStep(node.mark.line, node.mark.column, node.kind))
                if node.kind == "raise":
                    for state in current:
                        state.raised = True
                    ends.returns.extend(current)
                elif node.kind == "return":
                    ends.returns.extend(current)
                elif node.kind == "break":
                    ends.breaks.extend(current)
                else:
                    ends.continues.extend(current)
                current = []
        ends.normal.extend(current)
        return ends

    def loop(self, node: Loop, states: list[_State], ends: _Ends) -> list[_State]:
        exits: list[_State] = list(states) if node.may_skip else []
        seen = {self.signature(s) for s in states}
        frontier = [s.fork() if node.may_skip else s for s in states]
        for iteration in range(MAX_ITERATIONS):
            for state in frontier:
                state.step(PathStep(node.mark.line, node.mark.column, f"loop #{iteration + 1}"))
            sub = self.explore(node.body, frontier)
            ends.returns.extend(sub.returns)
            exits.extend(sub.breaks)
            after = [*sub.normal, *sub.continues]
            if node.ends_by_condition:
                exits.extend(after)
            fresh = []
            for state in after:
                signature = self.signature(state)
                if signature not in seen:
                    seen.add(signature)
                    fresh.append(state.fork() if node.ends_by_condition else state)
            if not fresh:
                break
            frontier = fresh
        else:
            self.bounds_hit.append(
                f"the loop at line {node.mark.line} after {MAX_ITERATIONS} iterations"
            )
        return self.merge(exits, f"line {node.mark.line}")

    def unrolled(self, node: Unrolled, states: list[_State], ends: _Ends) -> list[_State]:
        """A constant loop, iteration by iteration: `break` leaves it (skipping `else`),
        `continue` goes on with the next item."""
        broken: list[_State] = []
        current = states
        for number, body in enumerate(node.iterations, start=1):
            if not current:
                break
            for state in current:
                state.step(PathStep(node.mark.line, node.mark.column, f"iteration #{number}"))
            sub = self.explore(body, current)
            ends.returns.extend(sub.returns)
            broken.extend(sub.breaks)
            current = self.merge([*sub.normal, *sub.continues], f"line {node.mark.line}")
        sub = self.explore(node.orelse, current)
        ends.returns.extend(sub.returns)
        ends.breaks.extend(sub.breaks)
        ends.continues.extend(sub.continues)
        return self.merge([*sub.normal, *broken], f"line {node.mark.line}")

    def try_block(self, node: Try, states: list[_State], ends: _Ends) -> list[_State]:
        """Python's `try`: a raise in the body goes to the handlers (and on, unless
        one catches everything); `else` runs after a body that ended normally; the
        `finally` block runs on every way out, then the way out goes on — unless the
        `finally` block itself jumps, which replaces it."""
        sub = self.explore(node.body, states)
        raised = [s for s in sub.returns if s.raised]
        ways = _Ends(
            breaks=list(sub.breaks),
            continues=list(sub.continues),
            returns=[s for s in sub.returns if not s.raised],
        )
        still_raised: list[_State] = []
        if node.handlers and raised:
            catch_all = any(h.catches_all for h in node.handlers)
            for state in raised:
                for handler in node.handlers:
                    caught = state.fork()
                    caught.raised = False
                    caught.step(PathStep(handler.mark.line, handler.mark.column, "except"))
                    handled = self.explore(handler.body, [caught])
                    ways.normal.extend(handled.normal)
                    ways.breaks.extend(handled.breaks)
                    ways.continues.extend(handled.continues)
                    ways.returns.extend(s for s in handled.returns if not s.raised)
                    still_raised.extend(s for s in handled.returns if s.raised)
                if not catch_all:
                    still_raised.append(state)
        else:
            still_raised = raised
        after_else = self.explore(node.orelse, sub.normal)
        ways.normal.extend(after_else.normal)
        ways.breaks.extend(after_else.breaks)
        ways.continues.extend(after_else.continues)
        ways.returns.extend(s for s in after_else.returns if not s.raised)
        still_raised.extend(s for s in after_else.returns if s.raised)
        if not node.finalbody:
            ends.breaks.extend(ways.breaks)
            ends.continues.extend(ways.continues)
            ends.returns.extend([*ways.returns, *still_raised])
            return ways.normal
        normal: list[_State] = []
        for kind, group in (
            ("normal", ways.normal),
            ("break", ways.breaks),
            ("continue", ways.continues),
            ("return", ways.returns),
            ("raise", still_raised),
        ):
            if not group:
                continue
            for state in group:
                state.raised = False
                state.step(PathStep(node.mark.line, node.mark.column, "finally"))
            final = self.explore(node.finalbody, group)
            # A jump inside `finally` replaces the one in flight.
            ends.breaks.extend(final.breaks)
            ends.continues.extend(final.continues)
            ends.returns.extend(final.returns)
            resumed = final.normal
            if kind == "normal":
                normal.extend(resumed)
            elif kind == "break":
                ends.breaks.extend(resumed)
            elif kind == "continue":
                ends.continues.extend(resumed)
            elif kind == "return":
                ends.returns.extend(resumed)
            else:
                for state in resumed:
                    state.raised = True
                ends.returns.extend(resumed)
        return normal

    def signature(self, state: _State) -> tuple[Any, ...]:
        executive = self.executive(state)
        vehicle = executive.vehicle
        flying = isinstance(vehicle, FlightStateVehicle) and vehicle.flying
        preempted = frozenset((b, p) for b, (p, _) in state.preempted.items())
        return (executive.active_behaviors, flying, preempted)

    def merge(self, states: list[_State], where: str) -> list[_State]:
        best: dict[tuple[Any, ...], _State] = {}
        for state in states:
            signature = self.signature(state)
            known = best.get(signature)
            if known is None or len(state.steps) < len(known.steps):
                best[signature] = state
        kept = sorted(best.values(), key=lambda s: len(s.steps))
        if len(kept) > MAX_STATES:
            self.bounds_hit.append(f"{MAX_STATES} distinct states at {where}")
            kept = kept[:MAX_STATES]
        return kept

    # -- one call ------------------------------------------------------------------------
    def apply(self, state: _State, call: MissionCall) -> None:
        step = PathStep(call.mark.line, call.mark.column, call.kind, call.behavior or "(not known)")
        state.step(step)
        self.calling = call
        try:
            self.apply_call(state, call, step)
        finally:
            self.calling = None

    def apply_call(self, state: _State, call: MissionCall, step: PathStep) -> None:
        executive = self.executive(state)
        result = self.send(executive, call)
        state.actions = (*state.actions, call)
        name = call.behavior
        if result is None or name is None:
            if name is not None and call.kind == "execute":
                descriptor = self.catalog.behaviors.get(name)
                if descriptor is not None and descriptor.recurrent:
                    state.raised = True  # the API raises: the mission ends here
            return
        if call.kind == "inhibit":
            self.after_inhibit(state, step, call, result)
        else:
            self.after_activation(state, step, call, result, executive)

    def after_inhibit(
        self, state: _State, step: PathStep, call: MissionCall, result: ServiceResult
    ) -> None:
        name = call.behavior
        assert name is not None
        if result.ok:
            state.origin.pop(name, None)
            return
        if name in state.preempted:
            preemptor, by = state.preempted[name]
            self.report(
                INHIBIT_PREEMPTED,
                W,
                f"{call.shown} is rejected: {name} is no longer active, {preemptor} "
                f"preempted it at line {by.line}",
                step,
                state,
                name,
                preemptor,
            )

    def after_activation(
        self,
        state: _State,
        step: PathStep,
        call: MissionCall,
        result: ServiceResult,
        executive: Executive,
    ) -> None:
        name = call.behavior
        assert name is not None
        stand_in = self.classes[name]
        if not result.ok:
            self.rejected(state, step, call, result.error, stand_in)
            return
        for victim in result.payload.get("preempted", []):
            state.origin.pop(victim, None)
            if victim != name:
                state.preempted[victim] = (name, step)
        state.preempted.pop(name, None)
        state.origin[name] = step
        if stand_in.leaves is FlightState.LANDED:
            self.check_landing(state, step, name, executive)
        self.check_reach(state, step, call)
        if call.kind == "execute":
            state.origin.pop(name, None)
            if stand_in.leaves is not None:
                state.flight_change = step

    def rejected(
        self, state: _State, step: PathStep, call: MissionCall, error: str, stand_in: type
    ) -> None:
        name = call.behavior
        assert name is not None
        if NOT_FLYING in error or NOT_LANDED in error:
            wanted = "flying" if NOT_FLYING in error else "landed"
            change = state.flight_change
            if change is None:
                why = (
                    "no TAKE_OFF before it on this path"
                    if wanted == "flying"
                    else "it is flying from the start on this path"
                )
            else:
                left = "landed" if wanted == "flying" else "flying"
                why = f"{change.detail} at line {change.line} left it {left}"
            self.report(
                WRONG_FLIGHT_STATE,
                E,
                f"{call.shown} is rejected: {name} needs the vehicle {wanted}, and {why}",
                step,
                state,
                name,
            )
        elif "conflicts with active capability" in error:
            holders = [b for b in state.origin if b != name and b in error]
            held = "; ".join(
                f"{b} is still active (activated at line {state.origin[b].line})" for b in holders
            )
            self.report(
                CAPABILITY_CONFLICT,
                E,
                f"{call.shown} is rejected: {error.split(': ', 1)[-1]}"
                + (f"; {held}" if held else ""),
                step,
                state,
                name,
                *holders,
            )

    def check_landing(self, state: _State, step: PathStep, name: str, executive: Executive) -> None:
        needing = [
            b
            for b in executive.active_behaviors
            if b != name and self.classes[b].needs is FlightState.FLYING
        ]
        if not needing:
            return
        shown = ", ".join(
            f"{b} (activated at line {state.origin[b].line})" if b in state.origin else b
            for b in needing
        )
        self.report(
            LAND_WHILE_NEEDED,
            W,
            f"{name} starts while {shown} still {'needs' if len(needing) == 1 else 'need'} "
            "the vehicle flying",
            step,
            state,
            name,
            *needing,
        )

    def check_reach(self, state: _State, step: PathStep, call: MissionCall) -> None:
        name = call.behavior
        assert name is not None
        implementation = self.library.get(name)
        destinations: Mapping[str, str] = getattr(implementation, "destinations", {})
        descriptor = self.catalog.behaviors[name]
        altitude = getattr(implementation, "altitude", None)
        stand_in = self.classes[name]
        if call.kind == "execute" and state.position is not None:
            if stand_in.leaves is FlightState.FLYING and isinstance(altitude, (int, float)):
                x, y, _ = state.position
                state.position = (x, y, self.world.start[2] + float(altitude))
            elif stand_in.leaves is FlightState.LANDED:
                x, y, _ = state.position
                state.position = (x, y, self.world.start[2])
        if not destinations:
            return
        target: Vec3 | None = None
        for argument in call.arguments:
            spec = descriptor.argument(argument.name)
            kind = destinations.get(spec.name) if spec is not None else None
            value = argument.value
            if kind is None:
                continue
            if not (isinstance(value, list) and len(value) == 3 and is_known(value)):
                state.position = None
                return
            point = tuple(float(v) for v in value)
            if kind == "relative":
                if state.position is None:
                    return
                point = tuple(p + d for p, d in zip(state.position, point, strict=True))
            target = (point[0], point[1], point[2])
        if target is None:
            return
        if state.position is not None and descriptor.timeout is not None:
            horizontal, vertical, seconds = travel_between(
                state.position, target, self.world.limits
            )
            if seconds > descriptor.timeout:
                here = ", ".join(f"{c:g}" for c in state.position)
                there = ", ".join(f"{c:g}" for c in target)
                self.report(
                    TARGET_TOO_FAR,
                    W,
                    f"{call.shown} cannot reach ({there}) from ({here}) within its "
                    f"{descriptor.timeout:g} s timeout: {horizontal:.0f} m horizontally and "
                    f"{vertical:.0f} m vertically take at least {seconds:.0f} s at "
                    f"{describe_limits(self.world.limits)} ({self.world.name} world)",
                    step,
                    state,
                    name,
                )
        state.position = target if call.kind == "execute" else None

    def at_end(self, state: _State) -> None:
        """The mission returned on this path: recurrent behaviors still running?"""
        executive = self.executive(state)
        end = state.steps[-1] if state.steps else PathStep(1, 1, "end")
        for name in executive.active_behaviors:
            descriptor = self.catalog.behaviors.get(name)
            if descriptor is None or not descriptor.recurrent:
                continue
            started = state.origin.get(name, end)
            self.report(
                RECURRENT_LEFT_RUNNING,
                W,
                f"{name} (recurrent) is still running when the mission ends: nothing "
                "inhibits it on this path",
                started,
                state,
                name,
            )
