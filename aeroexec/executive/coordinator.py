"""The Behavior Coordinator: `activate_behavior`, `inhibit_behavior`, the active set.

Activation (Algorithm 3.5 with docs/design.md#the-repairs-of-the-thesis), in order:
unknown behavior -> format check -> situation -> consistency (who must be preempted)
-> capability check *as if* the victims were gone -> preempt victims (`INTERRUPTED`)
-> default values -> start. Every rejection happens before the first change, so a
rejected activation leaves the executive exactly as it was.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from aeroexec.executive.messages import BehaviorEvent, EventCode, ServiceResult, failure

if TYPE_CHECKING:
    from aeroexec.executive.behavior import Behavior
    from aeroexec.executive.executive import Executive

COORDINATOR = "behavior_coordinator"


class BehaviorCoordinator:
    def __init__(self, host: Executive) -> None:
        self.host = host
        self.catalog = host.catalog
        self.bus = host.bus
        self.specialist = host.specialist
        self.resources = host.resources
        #: name -> running behavior, in activation order.
        self.active: dict[str, Behavior] = {}
        self._uid = 0
        self._published: tuple[str, ...] | None = None

    @property
    def active_names(self) -> tuple[str, ...]:
        return tuple(sorted(self.active, key=self.catalog.order_of))

    # -- services ------------------------------------------------------------------------
    def activate_behavior(
        self, name: str, arguments: Mapping[str, Any] | None = None, caller: str = "mission"
    ) -> ServiceResult:
        args = dict(arguments or {})
        if self.bus.quiet():
            return self._activate(name, args)
        return self.bus.call(
            "activate_behavior",
            caller,
            lambda: self._activate(name, args),
            lambda: {"behavior": name, "arguments": args},
        )

    def inhibit_behavior(self, name: str, caller: str = "mission") -> ServiceResult:
        if self.bus.quiet():
            return self._inhibit(name)
        return self.bus.call(
            "inhibit_behavior", caller, lambda: self._inhibit(name), lambda: {"behavior": name}
        )

    # -- work ----------------------------------------------------------------------------
    def _activate(self, name: str, arguments: dict[str, Any]) -> ServiceResult:
        behavior = self.host.behaviors.get(name)
        if behavior is None:
            return failure(f"unknown behavior {name}{self._suggest(name)}")
        # The catalog's own (interned) string from here on: every index lookup below
        # then matches by identity instead of comparing characters.
        name = behavior.behavior_name
        form = self.specialist.check_behavior_format(COORDINATOR, name, arguments)
        if not form.ok:
            return form
        bus = self.bus
        situation = (
            behavior.situation()
            if bus.quiet()
            else bus.call(
                f"behavior_{name.lower()}/check_situation", COORDINATOR, behavior.situation
            )
        )
        if not situation.ok:
            return situation
        consistency = self.specialist.check_consistency(COORDINATOR, name, self.active)
        victims: list[str] = consistency.payload["inconsistent"]
        feasible = self.resources.check(name, victims)
        if not feasible.ok:
            return feasible
        defaults = self.specialist.default_values(COORDINATOR, name)
        self._uid += 1
        uid = self._uid
        with self.resources.batch():
            for victim in victims:
                self.active[victim].finish(EventCode.INTERRUPTED, f"preempted by {name}")
            self.resources.release_unneeded(keep_for=name)
            validated, timeout = form.payload["arguments"], defaults.payload["timeout"]
            started = (
                behavior.start(uid, validated, timeout)
                if bus.quiet()
                else bus.call(
                    f"behavior_{name.lower()}/start",
                    COORDINATOR,
                    lambda: behavior.start(uid, validated, timeout),
                    lambda: {"uid": uid, "arguments": validated},
                )
            )
            if started.ok and behavior.running:
                self.active[name] = behavior
        self._publish()
        if not started.ok:
            return started
        return ServiceResult(True, "", {"uid": uid, "preempted": victims})

    def _inhibit(self, name: str) -> ServiceResult:
        behavior = self.active.get(name)
        if behavior is None:
            return failure(f"{name} is not active")
        if self.bus.quiet():
            behavior.finish(EventCode.INTERRUPTED, "inhibited")
        else:
            self.bus.call(
                f"behavior_{name.lower()}/stop",
                COORDINATOR,
                lambda: _stopped(behavior.finish(EventCode.INTERRUPTED, "inhibited")),
            )
        self._publish()
        return ServiceResult(True)

    def on_behavior_event(self, event: BehaviorEvent) -> None:
        """A behavior ended (by itself, preempted or inhibited): forget it."""
        current = self.active.get(event.name)
        if current is not None and current.uid == event.uid:
            del self.active[event.name]
            self._publish()

    def _publish(self) -> None:
        if not self.bus.observed:
            return
        names = self.active_names
        if names != self._published:
            self._published = names
            self.bus.publish("list_of_active_behaviors", {"behaviors": list(names)})

    def _suggest(self, name: str) -> str:
        from aeroexec.catalog.loader import did_you_mean

        return did_you_mean(name, self.catalog.behaviors)


def _stopped(event: BehaviorEvent | None) -> ServiceResult:
    return ServiceResult(True) if event is not None else failure("was not running")
