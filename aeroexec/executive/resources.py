"""The Resource Manager: reference-counted capabilities and the processes behind them.

A process runs exactly while some referenced capability needs it. Processes start in
catalog order (the behavior's capability order, then each capability's process order)
and stop in the reverse of the order they started. Default capabilities are referenced
once at initiation and never drop to zero.

Two departures from the thesis, both deliberate:
* consistency is checked against *referenced* capabilities only (the thesis also
  counted ones whose count had fallen to zero but whose processes it had not yet
  stopped), so a preempting behavior may take a capability its victim just released;
* inside `batch()` (one activation with its preemptions) processes whose count falls to
  zero are stopped only at the end of the batch, and only if still unneeded, so a
  capability handed from victim to successor does not restart its processes.
"""

from __future__ import annotations

from collections.abc import Iterable
from types import TracebackType

from aeroexec.catalog.model import Catalog
from aeroexec.executive.bus import Bus
from aeroexec.executive.messages import OK, ServiceResult, failure
from aeroexec.executive.process import DroneProcess
from aeroexec.executive.specialist import BehaviorSpecialist

RESOURCE_MANAGER = "resource_manager"
DEFAULTS = "(default)"


class ResourceManager:
    def __init__(self, catalog: Catalog, bus: Bus, specialist: BehaviorSpecialist) -> None:
        self.catalog = catalog
        self.bus = bus
        self.specialist = specialist
        self.references: dict[str, int] = {}
        self.holders: dict[str, list[str]] = {}
        self.processes: dict[str, DroneProcess] = {}
        self._process_refs: dict[str, int] = {}
        self._start_order: list[str] = []
        self._batch_depth = 0
        self._published: list[tuple[str, int]] | None = None
        self._capability_order = {name: i for i, name in enumerate(catalog.capabilities)}
        self._batch = _Batch(self)

    # -- queries -------------------------------------------------------------------------
    @property
    def running_processes(self) -> tuple[str, ...]:
        return tuple(self._start_order)

    def referenced(self) -> frozenset[str]:
        return frozenset(self.references)

    def check(self, behavior: str, releasing: Iterable[str] = ()) -> ServiceResult:
        """Could `behavior` get its capabilities once `releasing` behaviors let theirs go?

        Asked before any preemption so that a rejected activation changes nothing.
        """
        expansion = self.specialist.capabilities_of(behavior)
        if isinstance(expansion, str):
            return failure(expansion)
        remaining = dict(self.references)
        for victim in releasing:
            released = self.specialist.capabilities_of(victim)
            if isinstance(released, str):
                continue
            for capability in released:
                if capability in remaining:
                    remaining[capability] -= 1
                    if remaining[capability] == 0:
                        del remaining[capability]
        new = tuple([c for c in expansion if c not in remaining])
        if not new:
            return OK
        problem = self.specialist.capability_conflict(new, frozenset(remaining))
        if problem:
            return failure(f"{behavior}: {problem}{self._held_by(problem, remaining)}")
        return OK

    def _held_by(self, problem: str, remaining: dict[str, int]) -> str:
        other = problem.rsplit(" ", 1)[-1]
        holders = [h for h in self.holders.get(other, []) if h]
        return f" (held by {', '.join(holders)})" if holders and other in remaining else ""

    # -- services ------------------------------------------------------------------------
    def initiate_resources(self, caller: str) -> ServiceResult:
        defaults = self.catalog.default_capabilities
        return self.bus.call(
            "initiate_resources",
            caller,
            lambda: self._initiate(defaults),
            lambda: {"capabilities": list(defaults)},
        )

    def activate_resources(self, behavior: str) -> ServiceResult:
        if self.bus.quiet():
            return self._activate(behavior)
        return self.bus.call(
            "activate_resources",
            f"behavior_{behavior.lower()}",
            lambda: self._activate(behavior),
            lambda: {"behavior": behavior},
        )

    def cancel_resources(self, behavior: str) -> ServiceResult:
        if self.bus.quiet():
            return self._cancel(behavior)
        return self.bus.call(
            "cancel_resources",
            f"behavior_{behavior.lower()}",
            lambda: self._cancel(behavior),
            lambda: {"behavior": behavior},
        )

    def batch(self) -> _Batch:
        """Defer stopping unneeded processes to the end of the block (`with batch():`)."""
        return self._batch

    def _end_batch(self) -> None:
        self._batch_depth -= 1
        if self._batch_depth == 0:
            self._sweep()
            self._publish()

    # -- work ----------------------------------------------------------------------------
    def _initiate(self, declared: tuple[str, ...]) -> ServiceResult:
        # A default capability holds the ones it requires for the whole session too.
        defaults = self.specialist.expand_capabilities(declared, "the default capabilities")
        if isinstance(defaults, str):
            return failure(f"default capabilities cannot be started: {defaults}")
        problem = self.specialist.capability_conflict(defaults, frozenset())
        if problem:
            return failure(f"default capabilities cannot all be active: {problem}")
        for capability in defaults:
            self._reference(capability, DEFAULTS)
        self._publish()
        return OK

    def _activate(self, behavior: str) -> ServiceResult:
        answer = self.specialist.behavior_resources(RESOURCE_MANAGER, behavior)
        if not answer.ok:
            return answer
        capabilities: list[str] = answer.payload["capabilities"]
        new = tuple([c for c in capabilities if c not in self.references])
        if new:
            consistent = self.specialist.check_capabilities_consistency(
                RESOURCE_MANAGER, new, tuple(self.references)
            )
            if not consistent.ok:
                return consistent
        for capability in capabilities:
            self._reference(capability, behavior)
        if not self._batch_depth:
            self._publish()
        return OK

    def _cancel(self, behavior: str) -> ServiceResult:
        expansion = self.specialist.capabilities_of(behavior)
        if isinstance(expansion, str):
            return failure(expansion)
        missing = [c for c in expansion if behavior not in self.holders.get(c, ())]
        if missing:
            return failure(f"{behavior} does not hold {', '.join(missing)}")
        for capability in reversed(expansion):
            self._release(capability, behavior)
        if not self._batch_depth:
            self._sweep()
            self._publish()
        return OK

    def _reference(self, capability: str, holder: str) -> None:
        count = self.references.get(capability, 0)
        self.references[capability] = count + 1
        self.holders.setdefault(capability, []).append(holder)
        if count:
            return
        for name in self.catalog.capabilities[capability].processes:
            refs = self._process_refs.get(name, 0)
            self._process_refs[name] = refs + 1
            if refs == 0 and name not in self._start_order:
                self._start_process(name)

    def _release(self, capability: str, holder: str) -> None:
        self.holders[capability].remove(holder)
        count = self.references[capability] - 1
        if count:
            self.references[capability] = count
            return
        del self.references[capability]
        del self.holders[capability]
        for name in self.catalog.capabilities[capability].processes:
            self._process_refs[name] -= 1

    def release_unneeded(self, keep_for: str) -> None:
        """Inside a batch, after the victims stopped and before `keep_for` starts: stop
        the processes nobody needs any more, except those `keep_for` is about to take,
        so an incoming controller never runs beside the one it replaces."""
        expansion = self.specialist.capabilities_of(keep_for)
        keep: set[str] = set()
        if not isinstance(expansion, str):
            for capability in expansion:
                keep.update(self.catalog.capabilities[capability].processes)
        self._sweep(keep)

    def _sweep(self, keep: set[str] | frozenset[str] = frozenset()) -> None:
        for name in reversed(list(self._start_order)):
            if self._process_refs.get(name, 0) <= 0 and name not in keep:
                self._stop_process(name)

    def _start_process(self, name: str) -> None:
        process = self.processes.get(name)
        if process is None:
            process = self.processes[name] = DroneProcess(name)
            process.set_up()
        process.start()
        self._start_order.append(name)
        if self.bus.observed:
            self.bus.publish("process_state", {"process": name, "state": "started"})

    def _stop_process(self, name: str) -> None:
        self.processes[name].stop()
        self._start_order.remove(name)
        if self.bus.observed:
            self.bus.publish("process_state", {"process": name, "state": "stopped"})

    def _publish(self) -> None:
        if not self.bus.observed:
            return
        order = self._capability_order
        current = sorted(self.references.items(), key=lambda item: order.get(item[0], -1))
        if current == self._published:
            return
        self._published = current
        self.bus.publish(
            "list_of_active_capabilities",
            {"capabilities": [{"name": n, "references": c} for n, c in current]},
        )


class _Batch:
    """`ResourceManager.batch()`: a plain context manager (a generator-based one costs
    more than the rest of an unobserved activation's bookkeeping); the nesting depth
    lives in the manager, so one instance serves every (nested) use."""

    __slots__ = ("_manager",)

    def __init__(self, manager: ResourceManager) -> None:
        self._manager = manager

    def __enter__(self) -> None:
        self._manager._batch_depth += 1

    def __exit__(
        self,
        kind: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._manager._end_batch()
