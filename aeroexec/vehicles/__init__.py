"""Vehicles the executive can drive: the `Vehicle` protocol and the built-in simulator.

The names are loaded when first used (PEP 562): reading a world file (`verify`) does
not import the simulator."""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from aeroexec.vehicles.base import Vehicle, VehicleCommandError, VehicleState
    from aeroexec.vehicles.sim import SimVehicle
    from aeroexec.vehicles.world import World, default_world, load_world, parse_world

__all__ = [
    "SimVehicle",
    "Vehicle",
    "VehicleCommandError",
    "VehicleState",
    "World",
    "default_world",
    "load_world",
    "parse_world",
]

#: Each public name -> the module defining it, imported when the name is first used.
_WHERE = {
    "SimVehicle": "sim",
    "Vehicle": "base",
    "VehicleCommandError": "base",
    "VehicleState": "base",
    "World": "world",
    "default_world": "world",
    "load_world": "world",
    "parse_world": "world",
}


def __getattr__(name: str) -> Any:
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
