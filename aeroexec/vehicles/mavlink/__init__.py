"""The live backend of the `Vehicle` protocol: ArduPilot Copter over MAVLink.

The implementation lives in the `aeroexec.mavlink` package (link, codec, frames, the
`mavsim` peer); this module is where `aeroexec.vehicles` users find it.
"""

from aeroexec.mavlink.endpoint import DEFAULT_GCS_URL, MavlinkError, parse_endpoint
from aeroexec.mavlink.vehicle import FAILSAFES, LinkTimeout, MavlinkConfig, MavlinkVehicle

__all__ = [
    "DEFAULT_GCS_URL",
    "FAILSAFES",
    "LinkTimeout",
    "MavlinkConfig",
    "MavlinkError",
    "MavlinkVehicle",
    "parse_endpoint",
]
