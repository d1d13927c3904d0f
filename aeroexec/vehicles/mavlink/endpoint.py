"""MAVLink connection strings, spelled as pymavlink's `mavutil.mavlink_connection` takes
them, loopback by default.

* `udpin:HOST:PORT` listens on HOST:PORT and answers whoever sent the autopilot's
  heartbeat (`udp:` is `udpin:`, as in mavutil);
* `udpout:HOST:PORT` sends to HOST:PORT from an ephemeral port and listens there;
* `tcp:HOST:PORT` connects to a TCP server (ArduPilot SITL's 5760, mavlink-router's
  5760, MAVProxy's `--out tcpin:`);
* `tcpin:HOST:PORT` listens for one TCP client (SITL started with `--serial0
  tcpclient:HOST:PORT`, a router's TCP client endpoint);
* `DEVICE` or `DEVICE,BAUD` is a serial port (`/dev/ttyACM0`, `/dev/ttyUSB0,57600`,
  `/dev/serial/by-id/...`); without `,BAUD` the caller's default baud rate applies.

Any network address that is not loopback is refused unless the caller allows remote
endpoints: a flight link is opened on purpose, never by a default. A serial device is a
local device: it needs no permission.
"""

from __future__ import annotations

import ipaddress
import re
import socket
from dataclasses import dataclass
from typing import Literal

from aeroexec.errors import AeroexecError

DEFAULT_GCS_URL = "udpin:127.0.0.1:14550"
DEFAULT_VEHICLE_URL = "udpout:127.0.0.1:14550"
#: pymavlink's default for a serial port (a USB autopilot ignores it; radios use 57600).
DEFAULT_BAUD = 115200

Kind = Literal["udpin", "udpout", "tcp", "tcpin", "serial"]
_SCHEMES: dict[str, Kind] = {
    "udpin": "udpin",
    "udp": "udpin",
    "udpout": "udpout",
    "tcp": "tcp",
    "tcpin": "tcpin",
}
_FORMS = (
    "udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT, tcpin:HOST:PORT or a serial "
    "device such as /dev/ttyUSB0,57600"
)


class MavlinkError(AeroexecError):
    """A MAVLink link cannot be opened or never came up (exit code 2 at the CLI)."""


@dataclass(frozen=True, slots=True)
class Endpoint:
    kind: Kind
    url: str
    #: Network endpoints: the numeric address and port.
    host: str = ""
    port: int = 0
    #: Serial endpoints: the device path and baud rate.
    device: str = ""
    baud: int = 0

    @property
    def address(self) -> tuple[str, int]:
        return (self.host, self.port)

    @property
    def serial(self) -> bool:
        return self.kind == "serial"

    @property
    def stream(self) -> bool:
        """A byte stream (TCP, serial) rather than datagrams (UDP)."""
        return self.kind in ("tcp", "tcpin", "serial")

    @property
    def loopback(self) -> bool:
        """Stays on this machine: a loopback address, or a local serial device."""
        return self.serial or ipaddress.ip_address(self.host).is_loopback


def parse_endpoint(url: str, *, allow_remote: bool = False, baud: int = DEFAULT_BAUD) -> Endpoint:
    """Read a connection string; `MavlinkError` naming what is wrong with it. `baud` is
    the rate of a serial device given without `,BAUD`."""
    text = url.strip()
    scheme, sep, rest = text.partition(":")
    if sep and scheme.lower() in _SCHEMES:
        return _network(text, _SCHEMES[scheme.lower()], rest, allow_remote)
    if text.startswith("/") or re.fullmatch(r"COM\d+(,.*)?", text, re.IGNORECASE):
        return _serial(text, baud)
    raise MavlinkError(f"unsupported connection '{url}' (use {_FORMS})")


def _network(url: str, kind: Kind, rest: str, allow_remote: bool) -> Endpoint:
    scheme = url.partition(":")[0]
    host, sep, port_text = rest.rpartition(":")
    if not sep or not host:
        raise MavlinkError(f"connection '{url}' needs HOST:PORT after '{scheme}:'")
    try:
        port = int(port_text)
    except ValueError:
        raise MavlinkError(f"connection '{url}': port '{port_text}' is not a number") from None
    if not 0 < port < 65536:
        raise MavlinkError(f"connection '{url}': port {port} is out of range 1..65535")
    address = _resolve(host, url, allow_remote)
    if not allow_remote and not ipaddress.ip_address(address).is_loopback:
        raise MavlinkError(
            f"connection '{url}' is not a loopback address; pass --allow-remote to fly "
            "over a real network"
        )
    if kind in ("tcp", "tcpin") and ":" in address:
        # pymavlink's TCP classes are IPv4 only.
        raise MavlinkError(f"connection '{url}': TCP over IPv6 is not supported (UDP is)")
    return Endpoint(kind, url, host=address, port=port)


def _serial(url: str, default_baud: int) -> Endpoint:
    device, sep, baud_text = url.rpartition(",")
    if not sep:
        device, baud_text = url, str(default_baud)
    try:
        baud = int(baud_text)
    except ValueError:
        raise MavlinkError(f"connection '{url}': baud rate '{baud_text}' is not a number") from None
    if baud <= 0:
        raise MavlinkError(f"connection '{url}': baud rate must be positive, got {baud}")
    if not device:
        raise MavlinkError(f"connection '{url}' names no serial device")
    return Endpoint("serial", url, device=device, baud=baud)


def _resolve(host: str, url: str, allow_remote: bool) -> str:
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
    try:
        return str(ipaddress.ip_address(host))
    except ValueError:
        pass
    if host.lower() == "localhost":
        return "127.0.0.1"
    if not allow_remote:
        raise MavlinkError(
            f"connection '{url}': host '{host}' is not a loopback address; pass "
            "--allow-remote to fly over a real network"
        )
    try:
        infos = socket.getaddrinfo(host, None, socket.AF_INET, socket.SOCK_DGRAM)
    except OSError as exc:
        raise MavlinkError(f"connection '{url}': cannot resolve '{host}': {exc}") from None
    return str(infos[0][4][0])
