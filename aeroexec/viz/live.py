"""`LiveView`: a session served live as it is recorded (`--live` on `run`, `fly`, `replay`).

    live = LiveView(LiveOptions(port=8765, rerun_port=9876), label="flight.mcap")
    simulate(SessionConfig(..., tap=live), observers=[live])
    live.close()

Two servers, both fed by the recorder's tap (`aeroexec.recording.tap`), never by an
encoder of their own (the second only when asked for):

* **Foxglove WebSocket** (`foxglove.sdk.v1`, the `foxglove-sdk` package): each channel of
  the recording, with its topic and schema, and each message with the recording's bytes
  and log time. Foxglove and Lichtblick (1.22 and later) connect to `ws://HOST:PORT`.
  A server drops what is logged before a viewer subscribes, so a new channel's messages
  are held until a viewer subscribes to it (or for `HOLD_S` with none): a viewer
  connected when a channel appears gets its first message too. The service
  `/abort_mission` ends the mission (the on-exit policy then applies); the catalog and
  the session's settings are parameters a viewer can read and cannot change.
* **Rerun gRPC** (`aeroexec.viz.live_rerun`, with `rerun_port`): the rows `aeroexec
  view` would write for the same recording, with the same blueprint. It costs most of
  the view's CPU (benchmarks/live.py), and rerun-sdk ~0.8 s of CPU to import: a
  Foxglove or Lichtblick user does not pay for it.

Both listen on 127.0.0.1 unless told otherwise (`--allow-remote`).
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import socket
import stat
import threading
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import foxglove
import orjson
from foxglove.websocket import Capability, ChannelView, Client, ServerListener, WebSocketServer

from aeroexec import interrupts
from aeroexec.errors import ViewerError
from aeroexec.executive.messages import ServiceCallRecord, TopicRecord
from aeroexec.recording.reader import ChannelInfo
from aeroexec.viz.ports import LOOPBACK, check_port_free

if TYPE_CHECKING:
    from aeroexec.executive.executive import Executive
    from aeroexec.viz.live_rerun import RerunLive

DEFAULT_FOXGLOVE_PORT = 8765
DEFAULT_RERUN_PORT = 9876
#: How long a new channel's messages wait for a viewer to subscribe (s).
HOLD_S = 1.0
#: How often held channels are looked at for their hold's end (s).
CHECK_S = 0.05
#: How long after a subscription its held messages are sent (s).
RELEASE_DELAY_S = 0.002
#: How many times a channel whose subscription the server refused is advertised again.
#: On a loaded machine (three live sessions on two cores) one channel was refused up to
#: ~10 times in a row when a burst of channels was advertised at once, and 5 tries lost
#: whole channels in 4 of 36 sessions; with 30, none of 18 lost a message.
READVERTISE = 30
#: The SDK's logger, and its line, for a subscription it refused.
SDK_CLIENT_LOGGER = "foxglove.websocket.connected_client"
_REFUSED = re.compile(r"attempted to subscribe to unknown channel: (\d+)")
#: Messages queued per viewer before the oldest are dropped (the SDK's default is 1024:
#: a viewer subscribing to held channels gets them in one burst).
BACKLOG = 1 << 16
#: After the session, how long the servers stay up for the last messages to leave (s).
LINGER_S = 0.3
#: The worker threads of foxglove-sdk's Tokio runtime, which it builds once, at its first
#: server, from Tokio's own TOKIO_WORKER_THREADS (default: one per core). A second worker
#: is woken to steal the sends of each tick's messages: with one, a real-time flight
#: with --live took 0.30 s of CPU instead of 0.34 s (interleaved flights), and one
#: serves a few viewers.
TOKIO_WORKERS = "1"
TOKIO_ENV = "TOKIO_WORKER_THREADS"
ABORT_SERVICE = "/abort_mission"
PARAMETER_PREFIX = "aeroexec/"


@dataclass(frozen=True, slots=True)
class LiveOptions:
    host: str = LOOPBACK
    #: The Foxglove WebSocket server's port (0: any free one).
    port: int = DEFAULT_FOXGLOVE_PORT
    #: The Rerun gRPC server's port (0: any free one); None: no Rerun stream.
    rerun_port: int | None = None
    #: Start the mission only once a viewer has subscribed.
    wait_viewer: bool = False
    #: What the mission's abort asks the session's ending for (`land`, `hold`, `none`).
    abort_action: str = "land"


def _json(value: object) -> bytes:
    return orjson.dumps(value)


@contextlib.contextmanager
def sdk_runtime() -> Iterator[None]:
    """Around foxglove-sdk's first server in a process: TOKIO_WORKER_THREADS set to
    `TOKIO_WORKERS` while the SDK builds its runtime, unless the user set a number of
    their own; then as it was (child processes do not inherit it). A value Tokio cannot
    read would panic inside the SDK: it is refused here, by name."""
    own = os.environ.get(TOKIO_ENV)
    if own is not None:
        if re.fullmatch("[0-9]+", own) is None or int(own) < 1:  # as Tokio reads it
            raise ViewerError(
                f"{TOKIO_ENV}={own!r} (the live servers' worker threads) is not a whole "
                "number above 0"
            )
        yield
        return
    os.environ[TOKIO_ENV] = TOKIO_WORKERS
    try:
        yield
    finally:
        os.environ.pop(TOKIO_ENV, None)


def _object_schema(name: str) -> foxglove.MessageSchema:
    data = _json({"type": "object", "title": name, "properties": {}})
    return foxglove.MessageSchema(
        encoding="json", schema=foxglove.Schema(name=name, encoding="jsonschema", data=data)
    )


def no_delay(port: int) -> int:
    """Set TCP_NODELAY on this process's connected TCP sockets whose local port is `port`
    (the Foxglove server's connections to its viewers); how many were set.

    foxglove-sdk 0.30's server leaves Nagle's algorithm on: a burst of small messages
    (a behavior's start: a dozen service calls in one tick) then waits for the viewer's
    delayed ACK, ~40 ms on Linux, before its second packet leaves. The sockets are the
    server's, in this process: they are found by their descriptors (Linux's
    /proc/self/fd; elsewhere /dev/fd), and set through a duplicate."""
    folder = "/proc/self/fd" if os.path.isdir("/proc/self/fd") else "/dev/fd"
    try:
        names = os.listdir(folder)
    except OSError:
        return 0
    done = 0
    for name in names:
        try:
            fd = int(name)
            if not stat.S_ISSOCK(os.fstat(fd).st_mode):
                continue
            duplicate = socket.socket(fileno=os.dup(fd))
        except (ValueError, OSError):
            continue
        with duplicate:
            try:
                if (
                    duplicate.type == socket.SOCK_STREAM
                    and duplicate.family in (socket.AF_INET, socket.AF_INET6)
                    and duplicate.getsockname()[1] == port
                ):
                    duplicate.getpeername()  # connected: not the listening socket
                    duplicate.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                    done += 1
            except OSError:
                continue
    return done


class FoxgloveLive(ServerListener):
    """The Foxglove WebSocket server: the recording's channels and messages, as written."""

    def __init__(self, options: LiveOptions, abort: Any) -> None:
        check_port_free(options.host, options.port, "the Foxglove WebSocket server")
        self._context = foxglove.Context()
        self._lock = threading.Lock()
        self._abort = abort
        self._wait = options.wait_viewer
        #: recording channel id -> the server's channel, and back
        self._channels: dict[int, foxglove.Channel] = {}
        self._recorded: dict[int, int] = {}
        #: recording channel id -> (log time, bytes) held until a viewer subscribes
        self._pending: dict[int, list[tuple[int, bytes]]] = {}
        self._since: dict[int, float] = {}
        #: server channel ids a viewer has subscribed to (written by the server's thread)
        self._subscribed: set[int] = set()
        self._viewer = threading.Event()
        self._clients: set[int] = set()
        self._next_check = 0.0
        #: recording channel id -> its server channel's `log` (the path of every message)
        self._logs: dict[int, Any] = {}
        #: set by a subscription: the releaser sends what was held for it at once
        self._wake = threading.Event()
        self._stopping = False
        self._releaser = threading.Thread(target=self._releasing, daemon=True)
        self._releaser.start()
        #: server channel ids whose subscription the server refused (`_readvertise`)
        self._refused: set[int] = set()
        #: recording channel id -> how many times it was advertised again
        self._again: dict[int, int] = {}
        self._log = logging.getLogger(SDK_CLIENT_LOGGER)
        self._log.addFilter(self._refusal)
        self._parameters: dict[str, str] = {}
        service = foxglove.Service(
            ABORT_SERVICE,
            schema=foxglove.ServiceSchema(
                "aeroexec.AbortMission",
                request=_object_schema("aeroexec.AbortMissionRequest"),
                response=_object_schema("aeroexec.AbortMissionResponse"),
            ),
            handler=self._on_abort,
        )
        with sdk_runtime():
            self.server = self._start_server(options, service)
        self.url = f"ws://{options.host}:{self.server.port}"

    def _start_server(self, options: LiveOptions, service: foxglove.Service) -> WebSocketServer:
        try:
            return foxglove.start_server(
                name="aeroexec",
                host=options.host,
                port=options.port,
                capabilities=[Capability.Services, Capability.Parameters],
                supported_encodings=["json"],
                services=[service],
                server_listener=self,
                context=self._context,
                message_backlog_size=BACKLOG,
            )
        except Exception as exc:  # the SDK raises its own RuntimeError kinds
            raise ViewerError(
                f"the Foxglove WebSocket server cannot listen on {options.host}:{options.port}: "
                f"{exc}"
            ) from None

    # -- the recorder's tap --------------------------------------------------------------
    def recording_started(
        self, metadata: Mapping[str, str], attachments: Mapping[str, bytes]
    ) -> None:
        values = {PARAMETER_PREFIX + key: value for key, value in metadata.items()}
        for name, data in attachments.items():
            if name in ("catalog.yaml", "world.yaml", "mission.py"):
                values[PARAMETER_PREFIX + name] = data.decode("utf-8", errors="replace")
        self._parameters = values

    def channel_added(self, channel: ChannelInfo) -> None:
        schema = foxglove.Schema(
            name=channel.schema_name, encoding=channel.schema_encoding, data=channel.schema_data
        )
        served = foxglove.Channel(
            channel.topic,
            schema=schema,
            message_encoding=channel.message_encoding,
            context=self._context,
        )
        with self._lock:
            self._channels[channel.id] = served
            self._logs[channel.id] = served.base.log
            self._recorded[served.id()] = channel.id
            self._pending[channel.id] = []
            self._since[channel.id] = time.monotonic()

    def message_written(self, channel_id: int, log_time_ns: int, data: bytes) -> None:
        if not (self._pending or self._refused):
            self._logs[channel_id](data, log_time_ns)
            return
        now = time.monotonic()
        if self._refused or now >= self._next_check:
            self._release(now)
        with self._lock:  # a held channel may be released by the releaser's thread
            held = self._pending.get(channel_id)
            if held is not None:
                held.append((log_time_ns, data))
            else:
                self._logs[channel_id](data, log_time_ns)

    def recording_closed(self) -> None:
        self.release_all()

    # -- viewers -------------------------------------------------------------------------
    def wait_for_viewer(self, keep: Callable[[], None] | None = None) -> None:
        """Until a viewer subscribes (a signal ends the wait), then a moment for the rest
        of its subscriptions, which come in one request. `keep` runs every 50 ms
        meanwhile (a live vehicle's link is served: its packets read, its heartbeats
        sent)."""
        while not self._viewer.wait(0.05):
            interrupts.check()
            if keep is not None:
                keep()
        time.sleep(0.1)
        self._release(time.monotonic())

    def release_all(self) -> None:
        """Send what is held for the channels a viewer subscribed to by now, giving a
        connected viewer up to `HOLD_S` to subscribe to the newest ones."""
        deadline = time.monotonic() + HOLD_S
        while self._pending and self._viewer.is_set() and time.monotonic() < deadline:
            self._release(time.monotonic())
            if self._pending:
                time.sleep(0.01)
        with self._lock:
            self._pending.clear()

    def _release(self, now: float) -> None:
        """Advertise refused channels again; send what is held for subscribed channels;
        end the hold of those no one subscribed to in time."""
        self._next_check = now + CHECK_S
        with self._lock:
            refused, self._refused = self._refused, set()
            for served_id in refused:
                channel_id = self._recorded.get(served_id)
                if channel_id is not None:
                    self._readvertise(channel_id, now)
            subscribed = self._subscribed
            viewer = self._viewer.is_set()
            for channel_id in list(self._pending):
                served = self._channels[channel_id]
                if served.id() in subscribed:
                    for log_time_ns, data in self._pending.pop(channel_id):
                        served.base.log(data, log_time_ns)
                elif (viewer or not self._wait) and now - self._since[channel_id] > HOLD_S:
                    del self._pending[channel_id]  # no one wants it: live from now on

    def _readvertise(self, channel_id: int, now: float) -> None:
        """foxglove-sdk 0.30's server refuses some subscriptions that come right after a
        channel's advertisement ("unknown channel"), a few in a hundred, and a viewer does
        not ask again. The channel is advertised anew (and its messages held until the
        viewer subscribes again), up to `READVERTISE` times."""
        tries = self._again.get(channel_id, 0)
        if tries >= READVERTISE:
            return
        self._again[channel_id] = tries + 1
        served = self._channels[channel_id]
        topic, schema, encoding = served.topic(), served.schema(), served.message_encoding
        served.close()  # first: the server advertises no second channel of a topic
        again = foxglove.Channel(
            topic, schema=schema, message_encoding=encoding, context=self._context
        )
        del self._recorded[served.id()]
        self._channels[channel_id] = again
        self._logs[channel_id] = again.base.log
        self._recorded[again.id()] = channel_id
        self._pending.setdefault(channel_id, [])
        self._since[channel_id] = now

    def _refusal(self, record: logging.LogRecord) -> bool:
        """The SDK's log of a refused subscription: the channel is advertised again (on
        the session's thread), and the line is not printed (it is handled)."""
        found = _REFUSED.search(record.getMessage())
        if found is None:
            return True
        self._refused.add(int(found[1]))
        return False

    def _releasing(self) -> None:
        """The releaser's thread: what was held for a channel leaves as soon as a viewer
        subscribes to it, not with the session's next message."""
        while True:
            self._wake.wait()
            if self._stopping:
                return
            time.sleep(RELEASE_DELAY_S)  # the server registers the subscription first
            self._wake.clear()
            with self._lock:
                for channel_id in list(self._pending):
                    served = self._channels[channel_id]
                    if served.id() in self._subscribed:
                        for log_time_ns, data in self._pending.pop(channel_id):
                            served.base.log(data, log_time_ns)

    # -- ServerListener (the server's thread) ---------------------------------------------
    def on_subscribe(self, client: Client, channel: ChannelView) -> None:
        # Without the lock (a set's add, a dict's store): the releaser holds it while it
        # hands messages to this server.
        if client.id not in self._clients:  # a new viewer: before its first message
            self._clients.add(client.id)
            no_delay(self.server.port)
        self._subscribed.add(channel.id)
        if not self._viewer.is_set():
            now = time.monotonic()  # held channels age from the first viewer on
            for channel_id in list(self._since):
                self._since[channel_id] = now
        self._viewer.set()
        self._wake.set()

    def on_unsubscribe(self, client: Client, channel: ChannelView) -> None:
        return None

    def on_get_parameters(
        self, client: Client, param_names: list[str], request_id: str | None = None
    ) -> list[foxglove.Parameter]:
        names = param_names or sorted(self._parameters)
        return [
            foxglove.Parameter(name, value=self._parameters[name])
            for name in names
            if name in self._parameters
        ]

    def on_set_parameters(
        self, client: Client, parameters: list[foxglove.Parameter], request_id: str | None = None
    ) -> list[foxglove.Parameter]:
        # What is recorded is not the viewer's to change: the values stay as they are.
        return self.on_get_parameters(client, [p.name for p in parameters])

    def _on_abort(self, request: foxglove.ServiceRequest) -> bytes:
        return _json(self._abort())

    def close(self) -> None:
        if self._viewer.is_set():
            time.sleep(LINGER_S)
        self._stopping = True
        self._wake.set()
        self._releaser.join(1)
        self.server.stop()
        self._log.removeFilter(self._refusal)


class LiveView:
    """Both servers, as one tap for the recorder and one observer of the session."""

    def __init__(self, options: LiveOptions, label: str = "live") -> None:
        self.options = options
        self._executive: Executive | None = None
        #: The mission script runs (an abort can stop it).
        self._mission = False
        self._abort_lock = threading.Lock()
        self.foxglove = FoxgloveLive(options, self._request_abort)
        self.rerun: RerunLive | None = None
        try:
            if options.rerun_port is not None:
                # Only when asked for: rerun-sdk costs ~0.8 s of CPU to import, and its
                # stream most of the view's CPU per message (benchmarks/live.py).
                from aeroexec.viz.live_rerun import RerunLive

                self.rerun = RerunLive(options.host, options.rerun_port, label)
        except BaseException:
            self.foxglove.server.stop()
            raise
        self._closed = False

    @property
    def urls(self) -> tuple[str, str | None]:
        return self.foxglove.url, self.rerun.url if self.rerun is not None else None

    # -- RecordTap -------------------------------------------------------------------------
    def recording_started(
        self, metadata: Mapping[str, str], attachments: Mapping[str, bytes]
    ) -> None:
        self.foxglove.recording_started(metadata, attachments)
        if self.rerun is not None:
            self.rerun.recording_started(metadata, attachments)

    def channel_added(self, channel: ChannelInfo) -> None:
        self.foxglove.channel_added(channel)
        if self.rerun is not None:
            self.rerun.channel_added(channel)

    def message_written(self, channel_id: int, log_time_ns: int, data: bytes) -> None:
        self.foxglove.message_written(channel_id, log_time_ns, data)
        if self.rerun is not None:
            self.rerun.message_written(channel_id, log_time_ns, data)

    def recording_closed(self) -> None:
        self.mission_ended()
        self.foxglove.recording_closed()
        if self.rerun is not None:
            self.rerun.recording_closed()

    # -- the session's observer --------------------------------------------------------------
    def on_service_call(self, record: ServiceCallRecord) -> None:
        return None

    def on_topic(self, record: TopicRecord) -> None:
        return None

    def session_started(self, executive: Executive) -> None:
        """The executive a viewer's abort stops; with `wait_viewer`, the mission waits
        here for a viewer."""
        self._executive = executive
        self._mission = True
        if self.options.wait_viewer:
            vehicle = executive.vehicle
            live = executive.clock.kind == "wall"  # a link to serve while it waits
            self.foxglove.wait_for_viewer((lambda: vehicle.step(0.0)) if live else None)

    def mission_ended(self) -> None:
        """The mission is over (its ending may still run): nothing left to abort."""
        with self._abort_lock:
            self._mission = False

    def session_ending(self, executive: Executive) -> None:
        self.mission_ended()

    def _request_abort(self) -> dict[str, object]:
        """A viewer's `/abort_mission` (on the server's thread): the mission is stopped at
        its next tick, and the session's ending (landing; `fly`: --on-exit) follows. Only
        the first call aborts; once the mission is over there is nothing to abort."""
        with self._abort_lock:
            executive = self._executive
            if executive is None or not self._mission:
                return {"ok": False, "error": "no mission is running"}
            self._mission = False
            action = self.options.abort_action
            executive.request_stop("aborted by a live viewer", action, by="abort")
        return {"ok": True, "action": action}

    def close(self) -> None:
        """Stop both servers (after a moment for the last messages to leave). Idempotent."""
        if self._closed:
            return
        self._closed = True
        try:
            self.foxglove.close()
        finally:
            if self.rerun is not None:
                self.rerun.close()


def loopback_or(allow_remote: bool) -> str:
    """The address the live servers listen on: this machine only, unless allowed."""
    return "0.0.0.0" if allow_remote else LOOPBACK


__all__ = [
    "DEFAULT_FOXGLOVE_PORT",
    "DEFAULT_RERUN_PORT",
    "LiveOptions",
    "LiveView",
    "loopback_or",
]
