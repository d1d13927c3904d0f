"""Vehicles the executive can drive: the `Vehicle` protocol and the built-in simulator."""

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
