"""ROS 2 service events (rosbag2's `<service>/_service_event` topics, Iron and later)
as aeroexec service calls: the one place a ROS 2 bag already carries a call log.

rosidl's event message (`service_msgs/ServiceEventInfo info`, `request[<=1]`,
`response[<=1]`) is published by the client (REQUEST_SENT=0, RESPONSE_RECEIVED=3) and
by the server (REQUEST_RECEIVED=1, RESPONSE_SENT=2), each as configured; the four
events of one call share `info.client_gid` and `info.sequence_number`. A call is
written when its first response event comes, at that time, with the request of its
first request event (or of the response event itself, which may carry it), on
`/<drone>/services/<service>` (the drone's namespace dropped), and its line in
`call_log`. A call whose response the bag does not hold is written at the end of the
import with `ok: false` and the error `no response recorded`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from aeroexec.bags.extract import plain

REQUEST_SENT, REQUEST_RECEIVED, RESPONSE_SENT, RESPONSE_RECEIVED = 0, 1, 2, 3
SERVICES = "services"
NO_RESPONSE = "no response recorded"


@dataclass(frozen=True, slots=True)
class Call:
    """One completed (or unanswered) call: the data of a service-call record."""

    topic: str
    data: dict[str, Any]
    request: object  # the decoded request message (for action results), or None


def _first(items: object) -> object | None:
    items = list(items or ())  # type: ignore[call-overload]
    return items[0] if items else None


def service_topic(service: str, drone: str) -> str:
    """The call channel (inside the drone's namespace) of a ROS 2 service name."""
    name = service.strip("/")
    prefix = f"{drone}/"
    if name.startswith(prefix):
        name = name[len(prefix) :]
    return f"{SERVICES}/{name}"


class ServiceCalls:
    """Pairs the events of each call (see the module docstring)."""

    def __init__(self, drone: str) -> None:
        self._drone = drone
        #: (service, client gid, sequence) -> (request message, first event time)
        self._open: dict[tuple[str, bytes, int], tuple[object, int]] = {}
        self._done: set[tuple[str, bytes, int]] = set()

    def event(self, service: str, message: object, time_ns: int) -> Call | None:
        info = getattr(message, "info", None)
        kind = getattr(info, "event_type", None)
        if not isinstance(kind, int):
            return None
        gid = bytes(plain(getattr(info, "client_gid", b"")) or b"")
        key = (service, gid, int(getattr(info, "sequence_number", 0)))
        if key in self._done:
            return None
        request = _first(getattr(message, "request", None))
        if kind in (REQUEST_SENT, REQUEST_RECEIVED):
            if key not in self._open:
                self._open[key] = (request, time_ns)
            return None
        response = _first(getattr(message, "response", None))
        asked, _ = self._open.pop(key, (request, time_ns))
        self._done.add(key)
        return self._call(service, gid, asked, {**_dict(response), "ok": True, "error": ""})

    def unanswered(self) -> list[Call]:
        """The calls without a response, in the order they were asked."""
        calls = [
            self._call(service, gid, request, {"ok": False, "error": NO_RESPONSE})
            for (service, gid, _), (request, _) in sorted(
                self._open.items(), key=lambda item: item[1][1]
            )
        ]
        self._open.clear()
        return calls

    def _call(self, service: str, gid: bytes, request: object, response: dict[str, Any]) -> Call:
        data = {
            "caller": f"client {gid.hex()[:16]}" if gid else "client",
            "service": service,
            "request": _dict(request),
            "response": response,
        }
        return Call(service_topic(service, self._drone), data, request)


def _dict(message: object) -> dict[str, Any]:
    value = plain(message) if message is not None else {}
    return value if isinstance(value, dict) else {"value": value}
