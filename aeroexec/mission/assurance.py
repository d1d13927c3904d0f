"""Runtime assurance in simulation: how a session ends when an observer asked it to stop
(`Executive.request_stop`), e.g. a property of `run --spec` with an `action`.

The mission has been stopped at a tick boundary (`StopRequested`); the executive keeps
stepping here, so the ending is recorded like any other part of the session:

* the behaviors still active are inhibited through the mission API (the recording shows
  the commands, as a live flight's ending does);
* `land`: the vehicle lands where it is; `rtl`: it flies home at its altitude, then lands;
  `hold`: it brakes and hovers; `abort`: nothing more (the session ends as it is).

A vehicle that refuses the command (a seized motor) is left as it is, and the actions
say so. Live flights use `aeroexec.mission.ending` instead (land, hold, the autopilot's
RTL).
"""

from __future__ import annotations

import math

from aeroexec.executive.clock import NS_PER_S
from aeroexec.executive.executive import Executive
from aeroexec.mission.api import MissionAPI
from aeroexec.vehicles.base import Vehicle, VehicleCommandError

ACTIONS = ("land", "hold", "rtl", "abort")
#: Simulated seconds a landing or a return may take before the ending gives up on it.
BOUND_S = 300.0


def carry_out(
    executive: Executive,
    api: MissionAPI,
    vehicle: Vehicle,
    action: str,
    home: tuple[float, float] = (0.0, 0.0),
) -> list[str]:
    """End the session with `action` (`rtl`: to `home`, x and y); what was done."""
    executive.stop_request = None  # the request has been honoured: step again
    done: list[str] = []
    for name in executive.active_behaviors:
        api.inhibit_behavior(name)
        done.append(f"inhibited {name}")
    try:
        if action == "land":
            vehicle.land()
            done.append("landing")
            _step_until(executive, lambda: not vehicle.state().flying)
        elif action == "rtl":
            state = vehicle.state()
            if state.flying:
                vehicle.go_to(home[0], home[1], max(state.position[2], 1.0))
                done.append("returning home")
                _step_until(executive, lambda: _near(vehicle, home))
                vehicle.land()
                done.append("landing")
                _step_until(executive, lambda: not vehicle.state().flying)
        elif action == "hold":
            vehicle.hover()
            done.append("holding")
            executive.step()
    except VehicleCommandError as exc:
        done.append(f"refused: {exc}")
    if vehicle.state().flying and action in ("land", "rtl"):
        done.append("still flying")
    return done


def _near(vehicle: Vehicle, home: tuple[float, float]) -> bool:
    x, y, _ = vehicle.state().position
    return math.hypot(x - home[0], y - home[1]) < 0.2


def _step_until(executive: Executive, done: object) -> None:
    limit = executive.clock.now_ns() + round(BOUND_S * NS_PER_S)
    while not done() and executive.clock.now_ns() < limit:  # type: ignore[operator]
        executive.step()
