"""The Behavior Specialist: the one component that knows the catalog.

Every answer comes from indexes built once (the catalog's preemption and conflict sets,
and the capability expansion per behavior cached on first use), so the cost of a
question grows with the active set, never with the catalog.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from aeroexec.catalog.arguments import check_arguments
from aeroexec.catalog.model import Catalog
from aeroexec.executive.bus import Bus
from aeroexec.executive.messages import OK, ServiceResult, failure

SPECIALIST = "behavior_specialist"


class BehaviorSpecialist:
    def __init__(self, catalog: Catalog, bus: Bus) -> None:
        self.catalog = catalog
        self.bus = bus
        self._resources: dict[str, tuple[str, ...] | str] = {}

    # -- services ------------------------------------------------------------------------
    def check_behavior_format(
        self, caller: str, name: str, arguments: Mapping[str, Any]
    ) -> ServiceResult:
        if self.bus.quiet():
            return self._check_format(name, arguments)
        return self.bus.call(
            "check_behavior_format",
            caller,
            lambda: self._check_format(name, arguments),
            lambda: {"behavior": name, "arguments": dict(arguments)},
        )

    def check_consistency(self, caller: str, name: str, active: Iterable[str]) -> ServiceResult:
        """Which active behaviors must stop for `name` to run (its incompatible lists;
        itself too when it is already active: a new activation restarts it)."""
        active = tuple(active)
        if self.bus.quiet():
            return self._consistency(name, active)
        return self.bus.call(
            "check_consistency",
            caller,
            lambda: self._consistency(name, active),
            lambda: {"behavior": name, "active_behaviors": list(active)},
        )

    def default_values(self, caller: str, name: str) -> ServiceResult:
        if self.bus.quiet():
            return self._defaults(name)
        return self.bus.call(
            "default_values", caller, lambda: self._defaults(name), lambda: {"behavior": name}
        )

    def behavior_resources(self, caller: str, name: str) -> ServiceResult:
        if self.bus.quiet():
            return self._resources_of(name)
        return self.bus.call(
            "behavior_resources",
            caller,
            lambda: self._resources_of(name),
            lambda: {"behavior": name},
        )

    def check_capabilities_consistency(
        self, caller: str, to_activate: tuple[str, ...], active: tuple[str, ...]
    ) -> ServiceResult:
        if self.bus.quiet():
            return self._capabilities_consistency(to_activate, active)
        return self.bus.call(
            "check_capabilities_consistency",
            caller,
            lambda: self._capabilities_consistency(to_activate, active),
            lambda: {"capabilities": list(to_activate), "active_capabilities": list(active)},
        )

    # -- answers -------------------------------------------------------------------------
    def _check_format(self, name: str, arguments: Mapping[str, Any]) -> ServiceResult:
        descriptor = self.catalog.behaviors.get(name)
        if descriptor is None:
            return failure(f"unknown behavior {name}")
        if not arguments and not descriptor.arguments:  # nothing to check, nothing to say
            return ServiceResult(True, "", {"arguments": {}})
        check = check_arguments(descriptor, arguments)
        if not check.ok:
            return failure("; ".join(check.errors))
        return ServiceResult(True, "", {"arguments": dict(check.values)})

    def _consistency(self, name: str, active: tuple[str, ...]) -> ServiceResult:
        victims = self.catalog.preempted_by(name)
        inconsistent = [b for b in active if b == name or b in victims]
        if len(inconsistent) > 1:
            inconsistent.sort(key=self.catalog.order_of)
        return ServiceResult(not inconsistent, "", {"inconsistent": inconsistent})

    def _defaults(self, name: str) -> ServiceResult:
        descriptor = self.catalog.behaviors.get(name)
        if descriptor is None:
            return failure(f"unknown behavior {name}")
        return ServiceResult(
            True, "", {"timeout": descriptor.timeout, "recurrent": descriptor.recurrent}
        )

    def _resources_of(self, name: str) -> ServiceResult:
        expansion = self.capabilities_of(name)
        if isinstance(expansion, str):
            return failure(expansion)
        return ServiceResult(True, "", {"capabilities": list(expansion)})

    def capabilities_of(self, name: str) -> tuple[str, ...] | str:
        """The behavior's capabilities in start order, required ones first (cached);
        an error text when one is undefined."""
        cached = self._resources.get(name)
        if cached is None:
            cached = self._expand(name)
            self._resources[name] = cached
        return cached

    def _expand(self, name: str) -> tuple[str, ...] | str:
        descriptor = self.catalog.behaviors.get(name)
        if descriptor is None:
            return f"unknown behavior {name}"
        return self.expand_capabilities(descriptor.capabilities, name)

    def expand_capabilities(
        self, capabilities: tuple[str, ...], needed_by: str
    ) -> tuple[str, ...] | str:
        """`capabilities` with the ones they require, prerequisites first, each once; an
        error text when one is undefined or requires itself."""
        order: list[str] = []
        visiting: set[str] = set()

        def visit(capability: str, needed_by: str) -> str | None:
            if capability in order:
                return None
            if capability in visiting:
                return f"capability {capability} requires itself (cycle through {needed_by})"
            spec = self.catalog.capabilities.get(capability)
            if spec is None:
                return f"capability {capability} needed by {needed_by} is not defined"
            visiting.add(capability)
            for required in spec.required_capabilities:
                problem = visit(required, capability)
                if problem:
                    return problem
            visiting.discard(capability)
            order.append(capability)
            return None

        for capability in capabilities:
            problem = visit(capability, needed_by)
            if problem:
                return problem
        return tuple(order)

    def _capabilities_consistency(
        self, to_activate: tuple[str, ...], active: tuple[str, ...]
    ) -> ServiceResult:
        problem = self.capability_conflict(to_activate, frozenset(active))
        return failure(problem) if problem else OK

    def capability_conflict(self, to_activate: tuple[str, ...], active: frozenset[str]) -> str:
        """'' when the new capabilities fit with each other and the referenced ones."""
        for i, capability in enumerate(to_activate):
            conflicts = self.catalog.conflicts_of(capability)
            if not conflicts:
                continue
            for other in to_activate[:i]:
                if other in conflicts:
                    return f"capabilities {other} and {capability} conflict"
            for other in sorted(conflicts & active):
                return f"capability {capability} conflicts with active capability {other}"
        return ""
