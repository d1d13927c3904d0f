"""A Foxglove WebSocket client (`foxglove.sdk.v1`) for the live tests and benchmarks.

Written from Foxglove's ws-protocol spec over aiohttp's WebSocket client, in a thread of
its own: it subscribes to every channel the server advertises, as it is advertised, and
keeps every message (its channel, log time, bytes and when it arrived); it can call a
service and read or set parameters. What aeroexec serves is checked against this, not
against the server's own library.
"""

from __future__ import annotations

import asyncio
import json
import struct
import threading
import time
from dataclasses import dataclass, field
from typing import Any

import aiohttp

SUBPROTOCOL = "foxglove.sdk.v1"
MESSAGE_DATA = 0x01
SERVICE_CALL_RESPONSE = 0x03
SERVICE_CALL_REQUEST = 0x02


@dataclass(frozen=True, slots=True)
class Received:
    topic: str
    log_time_ns: int
    data: bytes
    #: time.monotonic_ns() when it arrived
    arrived_ns: int


@dataclass
class FoxgloveClient:
    url: str
    channels: dict[int, dict[str, Any]] = field(default_factory=dict)
    services: dict[str, int] = field(default_factory=dict)
    messages: list[Received] = field(default_factory=list)
    server_info: dict[str, Any] = field(default_factory=dict)
    closed: threading.Event = field(default_factory=threading.Event)
    connected: threading.Event = field(default_factory=threading.Event)
    error: BaseException | None = None

    def __post_init__(self) -> None:
        self._loop = asyncio.new_event_loop()
        self._ws: aiohttp.ClientWebSocketResponse | None = None
        self._subscriptions: dict[int, int] = {}  # subscription id -> channel id
        self._responses: dict[int, asyncio.Future[bytes]] = {}
        self._parameters: dict[str, asyncio.Future[list[dict[str, Any]]]] = {}
        self._next = 1
        self._thread = threading.Thread(target=self._run, daemon=True)

    # -- the test's side ------------------------------------------------------------------
    def start(self, timeout: float = 15.0) -> FoxgloveClient:
        self._thread.start()
        if not self.connected.wait(timeout):
            raise AssertionError(f"could not connect to {self.url}: {self.error!r}")
        return self

    def wait_closed(self, timeout: float = 60.0) -> None:
        """Until the server closes the connection."""
        assert self.closed.wait(timeout), "the server did not close the connection"
        self._thread.join(5)

    def call(self, service: str, request: dict[str, Any], timeout: float = 10.0) -> Any:
        deadline = time.monotonic() + timeout
        while service not in self.services:
            assert time.monotonic() < deadline, f"no service {service}: {self.services}"
            time.sleep(0.01)
        answer = asyncio.run_coroutine_threadsafe(self._call(service, request), self._loop)
        return json.loads(answer.result(timeout))

    def parameters(self, names: list[str], set_to: dict[str, str] | None = None) -> dict[str, Any]:
        answer = asyncio.run_coroutine_threadsafe(self._params(names, set_to), self._loop)
        return {p["name"]: p.get("value") for p in answer.result(10)}

    def topics(self) -> dict[str, dict[str, Any]]:
        return {channel["topic"]: channel for channel in self.channels.values()}

    # -- the client's thread -------------------------------------------------------------
    def _run(self) -> None:
        try:
            self._loop.run_until_complete(self._session())
        except BaseException as exc:
            self.error = exc
        finally:
            self.closed.set()
            self.connected.set()

    async def _session(self) -> None:
        deadline = time.monotonic() + 15
        async with aiohttp.ClientSession() as session:
            while True:
                try:
                    ws = await session.ws_connect(self.url, protocols=(SUBPROTOCOL,))
                    break
                except aiohttp.ClientError:
                    if time.monotonic() > deadline:
                        raise
                    await asyncio.sleep(0.05)
            async with ws:
                assert ws.protocol == SUBPROTOCOL, ws.protocol
                self._ws = ws
                self.connected.set()
                async for message in ws:
                    if message.type == aiohttp.WSMsgType.TEXT:
                        await self._text(json.loads(message.data))
                    elif message.type == aiohttp.WSMsgType.BINARY:
                        self._binary(message.data)

    async def _text(self, message: dict[str, Any]) -> None:
        op = message["op"]
        if op == "serverInfo":
            self.server_info = message
        elif op == "advertise":
            subscriptions = []
            for channel in message["channels"]:
                self.channels[channel["id"]] = channel
                sub = self._next
                self._next += 1
                self._subscriptions[sub] = channel["id"]
                subscriptions.append({"id": sub, "channelId": channel["id"]})
            assert self._ws is not None
            await self._ws.send_str(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))
        elif op == "advertiseServices":
            for service in message["services"]:
                self.services[service["name"]] = service["id"]
        elif op == "parameterValues":
            waiting = self._parameters.pop(message.get("id", ""), None)
            if waiting is not None:
                waiting.set_result(message["parameters"])

    def _binary(self, data: bytes) -> None:
        if data[0] == MESSAGE_DATA:
            sub, log_time = struct.unpack_from("<IQ", data, 1)
            channel = self.channels[self._subscriptions[sub]]
            self.messages.append(
                Received(channel["topic"], log_time, data[13:], time.monotonic_ns())
            )
        elif data[0] == SERVICE_CALL_RESPONSE:
            _service, call, length = struct.unpack_from("<III", data, 1)
            self._responses.pop(call).set_result(data[13 + length :])

    async def _call(self, service: str, request: dict[str, Any]) -> bytes:
        call = self._next
        self._next += 1
        future: asyncio.Future[bytes] = self._loop.create_future()
        self._responses[call] = future
        encoding = b"json"
        payload = json.dumps(request).encode()
        header = struct.pack(
            "<BIII", SERVICE_CALL_REQUEST, self.services[service], call, len(encoding)
        )
        assert self._ws is not None
        await self._ws.send_bytes(header + encoding + payload)
        return await future

    async def _params(
        self, names: list[str], set_to: dict[str, str] | None
    ) -> list[dict[str, Any]]:
        key = f"q{self._next}"
        self._next += 1
        future: asyncio.Future[list[dict[str, Any]]] = self._loop.create_future()
        self._parameters[key] = future
        assert self._ws is not None
        if set_to is not None:
            parameters = [{"name": k, "value": v} for k, v in set_to.items()]
            await self._ws.send_str(
                json.dumps({"op": "setParameters", "parameters": parameters, "id": key})
            )
        else:
            await self._ws.send_str(
                json.dumps({"op": "getParameters", "parameterNames": names, "id": key})
            )
        return await future
