"""Vehicles the executive can drive: the `Vehicle` protocol and the built-in simulator.

The names are loaded when first used (PEP 562): reading a world file (`verify`) does
not import the simulator."""

from __future__ import annotations

from typing import TYPE_CHECKING

from aeroexec.lazy import lazy_exports

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


__getattr__, __dir__ = lazy_exports(__name__, _WHERE, globals())
