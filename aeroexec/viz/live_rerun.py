"""`RerunLive`: the Rerun gRPC stream of a live view (`--live --rerun-port PORT`).

What `aeroexec view` would write for the recording, row for row: each message the
recorder's tap hands over is read as the reader reads the file (`decode_record`) into the
same `SessionConverter`, with the same blueprint, and sent through rerun-sdk's own
`GrpcServerSink`. Rerun's server keeps what was sent, so a viewer that connects late
still gets the whole session. In a module of its own: rerun-sdk is imported only when
the stream is asked for (~0.8 s of CPU a start).
"""

from __future__ import annotations

import contextlib
import time
import uuid
from collections.abc import Mapping

import rerun as rr

from aeroexec.errors import WorldError
from aeroexec.recording.reader import ChannelInfo, decode_record
from aeroexec.recording.schemas import SERVICE_CALL
from aeroexec.vehicles.world import parse_world
from aeroexec.viz.blueprint import build_blueprint
from aeroexec.viz.columns import ColumnWriter
from aeroexec.viz.convert import SessionConverter, draws
from aeroexec.viz.layout import layouts_for
from aeroexec.viz.ports import check_port_free, free_port
from aeroexec.viz.scene import WORLD_ATTACHMENT, log_view_coordinates, trajectory_color
from aeroexec.viz.view import APPLICATION_ID, start_source

#: How often the Rerun rows held by the column writer are sent (s of wall time). Each
#: send costs ~2.5 ms of CPU (a chunk per entity with new rows, built by rerun-sdk's
#: Python): every 0.2 s (Rerun's own batcher's pace) that was ~0.4 s of CPU in a 28 s
#: real-time flight, ~2x the flight's own; every 0.5 s ~0.2 s. The Rerun view moves
#: twice a second; the Foxglove server is the low-latency path.
RERUN_SEND_S = 0.5


class RerunLive:
    """The Rerun gRPC stream: what `view` would write for the recording, row for row."""

    def __init__(self, host: str, port: int, label: str) -> None:
        port = port or free_port(host)
        check_port_free(host, port, "the Rerun gRPC server")
        self._label = label
        (self._layout,) = layouts_for([label])
        self.stream = rr.RecordingStream(
            APPLICATION_ID, recording_id=str(uuid.uuid4()), send_properties=False
        )
        self.stream.set_log_time_enabled(False)
        self.stream.set_log_tick_enabled(False)
        sink = rr.GrpcServerSink(bind_ip=host, port=port)
        self.stream.set_sinks(sink, default_blueprint=build_blueprint([self._layout]))
        log_view_coordinates(self.stream)
        self.url = f"rerun+http://{host}:{port}/proxy"
        self._writer = ColumnWriter(self.stream)
        #: channel id -> (the channel, whether its messages become rows)
        self._channels: dict[int, tuple[ChannelInfo, bool]] = {}
        self._prefix = "/"
        self._converter: SessionConverter | None = None
        self._sim = True
        self._world = None
        self._sent = time.monotonic()
        self._finished = False

    def recording_started(
        self, metadata: Mapping[str, str], attachments: Mapping[str, bytes]
    ) -> None:
        self._sim = metadata.get("clock") == "sim"
        self._prefix = f"/{metadata.get('drone', 'drone1')}/"
        world_text = attachments.get(WORLD_ATTACHMENT)
        if world_text is not None:
            with contextlib.suppress(WorldError):
                self._world = parse_world(world_text.decode("utf-8", errors="replace"), "world")
        self.stream.send_recording_name(self._label)
        start_source(
            self.stream,
            self._layout,
            {"file": self._label, **metadata},
            self._world,
            trajectory_color(0),
        )

    def channel_added(self, channel: ChannelInfo) -> None:
        name = channel.topic.removeprefix(self._prefix)
        self._channels[channel.id] = (channel, channel.schema_name == SERVICE_CALL or draws(name))

    def message_written(self, channel_id: int, log_time_ns: int, data: bytes) -> None:
        channel, drawn = self._channels[channel_id]
        converter = self._converter
        if converter is not None and not drawn:
            converter.pass_over(log_time_ns)  # not decoded: most of a flight's messages
            return
        record = decode_record(channel, log_time_ns, data)
        if record is None:
            return
        if converter is None:
            converter = self._converter = SessionConverter(
                self.stream,
                self._writer,
                self._layout,
                origin_ns=0 if self._sim else log_time_ns,
                world=self._world,
                color=trajectory_color(0),
            )
        converter.feed(record)
        now = time.monotonic()
        if now - self._sent >= RERUN_SEND_S:
            self._writer.flush()
            self._sent = now

    def recording_closed(self) -> None:
        if self._finished:
            return
        self._finished = True
        if self._converter is not None:
            self._converter.finish()
        self._writer.flush()
        self.stream.flush()

    def close(self) -> None:
        self.recording_closed()
        self.stream.disconnect()
