"""MAVLink connection strings (`udpin:HOST:PORT`, `udpout:HOST:PORT`), loopback by default.

The spelling is pymavlink's (`mavutil.mavlink_connection`): `udpin` listens on HOST:PORT
and answers whoever sent the autopilot's heartbeat; `udpout` sends to HOST:PORT from an
ephemeral port and listens for the answers there. `udp:` is `udpin:`, as in mavutil.
Anything that is not loopback is refused unless the caller allows remote endpoints: a
flight link is opened on purpose, never by a default.
"""

from __future__ import annotations

import ipaddress
import socket
from dataclasses import dataclass
from typing import Literal

from aeroexec.errors import AeroexecError

DEFAULT_GCS_URL = "udpin:127.0.0.1:14550"
DEFAULT_VEHICLE_URL = "udpout:127.0.0.1:14550"

Direction = Literal["udpin", "udpout"]
_SCHEMES: dict[str, Direction] = {"udpin": "udpin", "udp": "udpin", "udpout": "udpout"}


class MavlinkError(AeroexecError):
    """A MAVLink link cannot be opened or never came up (exit code 2 at the CLI)."""


@dataclass(frozen=True, slots=True)
class Endpoint:
    direction: Direction
    host: str
    port: int
    url: str

    @property
    def address(self) -> tuple[str, int]:
        return (self.host, self.port)

    @property
    def loopback(self) -> bool:
        return ipaddress.ip_address(self.host).is_loopback


def parse_endpoint(url: str, *, allow_remote: bool = False) -> Endpoint:
    """Read a connection string; `MavlinkError` naming what is wrong with it."""
    text = url.strip()
    scheme, sep, rest = text.partition(":")
    if not sep or scheme.lower() not in _SCHEMES:
        raise MavlinkError(
            f"unsupported connection '{url}' (use udpin:HOST:PORT or udpout:HOST:PORT)"
        )
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
    return Endpoint(_SCHEMES[scheme.lower()], address, port, text)


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
