"""Vehicle faults end the behaviors that list them, through the base class, in any vehicle."""

from __future__ import annotations

from dataclasses import replace

from aeroexec.catalog import DEFAULT_CATALOG, load_catalog
from aeroexec.executive import Behavior, EventCode, Executive, GenericBehavior
from aeroexec.vehicles.base import VehicleState
from aeroexec.vehicles.null import NullVehicle

FLYING = VehicleState((0.0, 0.0, 1.0), (0.0, 0.0, 0.0), 0.0, 0.9, True, True)


class FaultyVehicle(NullVehicle):
    """Holds still in the air; `fault` can be set by the test."""

    def __init__(self) -> None:
        super().__init__(FLYING)
        self.fault = ""

    def state(self) -> VehicleState:
        return replace(super().state(), fault=self.fault)


class Moving(Behavior):
    name = "GO_TO_POINT"
    fails_on_faults = ("link_lost",)


class Listening(Behavior):
    name = "PAY_ATTENTION_TO_VISUAL_MARKERS"


def test_listed_fault_fails_the_behavior_and_others_go_on() -> None:
    vehicle = FaultyVehicle()
    library = {cls.name: cls for cls in (Moving, Listening)}
    ex = Executive(
        load_catalog(DEFAULT_CATALOG), vehicle=vehicle, library=library, stand_in=GenericBehavior
    )
    assert ex.activate_behavior("PAY_ATTENTION_TO_VISUAL_MARKERS").ok
    assert ex.activate_behavior("GO_TO_POINT", {"coordinates": [1, 1, 1]}).ok
    ex.run_for(1.0)
    assert ex.events == []  # no fault, nothing ends
    vehicle.fault = "stuck_motor"  # not listed: the behavior judges it itself
    ex.run_for(1.0)
    assert ex.events == []
    vehicle.fault = "link_lost"
    ex.step()
    assert [(e.name, e.code, e.detail) for e in ex.events] == [
        ("GO_TO_POINT", EventCode.PROCESS_FAILURE, "vehicle fault: link_lost")
    ]
    assert ex.active_behaviors == ("PAY_ATTENTION_TO_VISUAL_MARKERS",)
    assert "SETPOINT_BASED_FLIGHT_CONTROL" not in ex.capability_references


def test_standard_motion_behaviors_and_land_fail_on_a_lost_link() -> None:
    from aeroexec.behaviors import STANDARD_LIBRARY

    failing = {n for n, cls in STANDARD_LIBRARY.items() if "link_lost" in cls.fails_on_faults}
    assert {"TAKE_OFF", "LAND", "GO_TO_POINT", "ROTATE", "FLIP", "START_MOVING"} <= failing
    assert "WAIT" not in failing and "BROADCAST_MESSAGE" not in failing


def test_default_capabilities_hold_what_they_require() -> None:
    """A default capability's required capabilities start at initiation, before it, and
    stay referenced (the verifier's AX205 witness relies on the same rule)."""
    from aeroexec.catalog import parse_catalog

    catalog = parse_catalog(
        """
behavior_descriptors:
  - behavior: HOVER
    timeout: 5
    recurrent: no
capability_descriptors:
  - capability: LOCALIZATION
    active_by_default: yes
    processes: [localizer]
    required_capabilities: [ODOMETRY]
  - capability: ODOMETRY
    active_by_default: no
    processes: [odometry]
""",
        "req.yaml",
    )
    ex = Executive(catalog, vehicle=NullVehicle(), library={}, stand_in=GenericBehavior)
    assert ex.initiation.ok
    assert ex.capability_references == {"ODOMETRY": 1, "LOCALIZATION": 1}
    assert ex.running_processes == ("odometry", "localizer")
