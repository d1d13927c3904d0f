"""`NullVehicle`: an aircraft that stays where it is and never refuses.

For exercising a catalog without physics: verifier witnesses, generated catalogs in
property tests, and the activation benchmark (so it measures the executive, not a
simulator).
"""

from __future__ import annotations

from aeroexec.vehicles.base import Vec3, VehicleState

_GROUNDED = VehicleState((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0, 1.0, False, False)


class NullVehicle:
    kind = "null"

    def __init__(self, state: VehicleState = _GROUNDED) -> None:
        self._state = state

    def step(self, dt: float) -> None:
        pass

    def state(self) -> VehicleState:
        return self._state

    def take_off(self, altitude: float) -> None:
        pass

    def land(self) -> None:
        pass

    def go_to(self, x: float, y: float, z: float) -> None:
        pass

    def set_velocity(self, vx: float, vy: float, vz: float) -> None:
        pass

    def set_yaw(self, yaw: float) -> None:
        pass

    def hover(self) -> None:
        pass

    def flip(self, direction: str) -> None:
        pass

    def visible_markers(self) -> tuple[int, ...]:
        return ()

    def visible_object(self) -> Vec3 | None:
        return None
