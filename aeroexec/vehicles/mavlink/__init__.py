"""The live backend of the `Vehicle` protocol: ArduPilot Copter in GUIDED mode over MAVLink.

* `endpoint` — connection strings (`udpin:`, `udpout:`, `tcp:`, `tcpin:`, serial
  `DEVICE[,BAUD]`), loopback unless allowed;
* `transport` — UDP sockets, and byte streams (TCP, serial) through `streams`, pymavlink's
  own connection classes fitted to a flight link;
* `codec` — bytes <-> messages (per datagram, or a stream's); recordable packet dictionaries;
* `convert` — ENU <-> NED, yaw <-> heading, ArduCopter mode numbers;
* `link` — a transport, the codec, signing, counters, the recording tap;
* `telemetry` — received messages folded into `VehicleState` (non-finite ones refused);
* `vehicle` — `MavlinkVehicle`, the `Vehicle` protocol over MAVLink, link loss, failsafes.

The names below are what a caller needs to fly; the tools built on this backend (the
`mavsim` peer, the `.tlog` reader) are in `aeroexec.mavlink`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from aeroexec.lazy import lazy_exports

if TYPE_CHECKING:
    from aeroexec.vehicles.mavlink.endpoint import DEFAULT_GCS_URL, MavlinkError, parse_endpoint
    from aeroexec.vehicles.mavlink.vehicle import (
        FAILSAFES,
        LinkTimeout,
        MavlinkConfig,
        MavlinkVehicle,
    )

__all__ = [
    "DEFAULT_GCS_URL",
    "FAILSAFES",
    "LinkTimeout",
    "MavlinkConfig",
    "MavlinkError",
    "MavlinkVehicle",
    "parse_endpoint",
]

#: Each public name -> the module defining it, imported when the name is first used, so
#: that the `mavsim` peer or the `.tlog` reader, importing the codec, does not also load
#: `MavlinkVehicle`.
_WHERE = {
    "DEFAULT_GCS_URL": "endpoint",
    "FAILSAFES": "vehicle",
    "LinkTimeout": "vehicle",
    "MavlinkConfig": "vehicle",
    "MavlinkError": "endpoint",
    "MavlinkVehicle": "vehicle",
    "parse_endpoint": "endpoint",
}


__getattr__, __dir__ = lazy_exports(__name__, _WHERE, globals())
