"""The MCAP side of an import: an aeroexec-profile file with two kinds of channels.

* Raw channels, one per bag connection, topic `/ros1<original topic>` (e.g.
  `/ros1/drone1/behavior_event`) for a ROS 1 bag, `/ros2<original topic>` for a ROS 2
  one: the connection's definition as schema (ROS 1: encoding `ros1msg`, named with its
  ROS 1 type; ROS 2: `ros2msg` or `ros2idl`, named `pkg/msg/Name`, the full
  concatenated text), message encoding `ros1` or `cdr`, the serialized bytes exactly as
  in the bag; channel metadata `topic` (the original name), ROS 1's `md5sum`,
  `callerid` and `latching`, ROS 2's `offered_qos_profiles` and `topic_type_hash`, when
  the bag has them. The prefix keeps them apart from the aeroexec channels, several of
  which have Aerostack's own names (`/drone1/behavior_event`), while Foxglove and `mcap`
  still decode them.
* aeroexec channels `/<drone>/<name>` with the profile's JSON Schemas (what the
  `Recorder` writes; see aeroexec/recording/schemas.py).

Messages are written in the order given (the importer gives bag time order); sequence
numbers count messages from 0. Nothing depends on the clock or the host, so the same
bag and mapping give the same file.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import IO, Any

from mcap.writer import CompressionType, Writer

from aeroexec.bags.bagfile import BagConnection
from aeroexec.recording.foxglove import call_log_message
from aeroexec.recording.schemas import (
    MESSAGE_ENCODING,
    PROFILE,
    SCHEMA_ENCODING,
    SERVICE_CALL,
    schema_for,
    schema_name_for_topic,
)
from aeroexec.recording.writer import LIBRARY, METADATA_NAME, encode_json

RAW_PREFIX = "/ros1"
RAW_PREFIXES = {1: "/ros1", 2: "/ros2"}
_COMPRESSION_TYPES = {
    "lz4": CompressionType.LZ4,
    "zstd": CompressionType.ZSTD,
    "none": CompressionType.NONE,
}
COMPRESSIONS = tuple(_COMPRESSION_TYPES)
#: mcap's Writer builds a chunk in a BytesIO and copies it out to compress: a chunk that
#: stays in the CPU cache writes ~10 % faster than 1 MiB ones (the mission bag's 32,700
#: records: 135 vs 155 ms), for a file 0.7 % larger. No flush bound: an import is only
#: useful whole (it is written to a temporary name and renamed into place).
CHUNK_SIZE = 256 * 1024


def writer_options(compression: str) -> dict[str, Any]:
    """The keyword arguments of mcap's `Writer` for an import (the benchmark's floor
    writes with the same)."""
    return {"chunk_size": CHUNK_SIZE, "compression": _COMPRESSION_TYPES[compression]}


def raw_topic(topic: str, ros_version: int = 1) -> str:
    return RAW_PREFIXES[ros_version] + topic


class ImportSink:
    def __init__(
        self, stream: IO[bytes], drone: str, compression: str = "lz4", ros_version: int = 1
    ) -> None:
        if compression not in COMPRESSIONS:
            raise ValueError(f"compression must be one of {COMPRESSIONS}")
        self._ros_version = ros_version
        self._writer = Writer(stream, **writer_options(compression))
        self._prefix = f"/{drone}/"
        self._schemas: dict[tuple[str, str, bytes], int] = {}
        self._raw: dict[int, int] = {}  # bag connection id -> channel id
        self._json: dict[str, int] = {}  # aeroexec topic -> channel id
        self._add_message = self._writer.add_message
        self._sequence = 0
        self._call_seq = 0
        #: aeroexec topic -> messages written (derived channels only).
        self.derived: dict[str, int] = {}
        self._derived_total = 0

    def start(
        self, metadata: Mapping[str, Mapping[str, str]], attachments: Mapping[str, bytes]
    ) -> None:
        self._writer.start(profile=PROFILE, library=LIBRARY)
        for name, values in metadata.items():
            self._writer.add_metadata(name, dict(values))
        for name, data in attachments.items():
            # create/log time 0: the same bag must give the same bytes.
            self._writer.add_attachment(0, 0, name, "application/yaml", data)

    # -- channels ----------------------------------------------------------------------------
    def _schema(self, name: str, encoding: str, data: bytes) -> int:
        key = (name, encoding, data)
        schema = self._schemas.get(key)
        if schema is None:
            schema = self._writer.register_schema(name, encoding, data)
            self._schemas[key] = schema
        return schema

    def raw_channel(self, connection: BagConnection) -> int:
        channel = self._raw.get(connection.id)
        if channel is None:
            schema = 0  # none: a ROS 2 type without any known definition
            if connection.schema_encoding:
                schema = self._schema(
                    connection.schema_name or connection.type,
                    connection.schema_encoding,
                    connection.msgdef.encode("utf-8"),
                )
            metadata = {"topic": connection.topic}
            if connection.md5sum:
                metadata["md5sum"] = connection.md5sum
            if connection.callerid is not None:
                metadata["callerid"] = connection.callerid
            if connection.latching is not None:
                metadata["latching"] = "true" if connection.latching else "false"
            metadata.update(connection.extra)
            channel = self._writer.register_channel(
                raw_topic(connection.topic, self._ros_version),
                connection.encoding,
                schema,
                metadata,
            )
            self._raw[connection.id] = channel
        return channel

    def _json_channel(self, topic: str, schema_name: str) -> int:
        channel = self._json.get(topic)
        if channel is None:
            definition = schema_for(schema_name)
            schema = self._schema(definition.name, SCHEMA_ENCODING, definition.data)
            channel = self._writer.register_channel(
                self._prefix + topic, MESSAGE_ENCODING, schema, {}
            )
            self._json[topic] = channel
        return channel

    # -- messages ----------------------------------------------------------------------------
    def raw(self, connection: BagConnection, log_time_ns: int, data: bytes) -> None:
        """A bag message on its raw channel (registered first: `raw_channel`). The one
        call per bag message: it does nothing but hand the bytes to mcap."""
        self._add_message(self._raw[connection.id], log_time_ns, data, log_time_ns, self._sequence)
        self._sequence += 1

    @property
    def raw_messages(self) -> int:
        """Bag messages written (every message is numbered, raw and derived alike)."""
        return self._sequence - self._derived_total

    def derived_message(
        self, topic: str, log_time_ns: int, data: dict[str, Any], call: bool = False
    ) -> None:
        """An aeroexec-profile message on `/<drone>/<topic>` (`call`: a service call
        record, numbered here in write order, made at the top: it has no `parent_seq`,
        and its line in `call_log`)."""
        if call:
            data = {"seq": self._call_seq, **data}
            self._call_seq += 1
            channel = self._json_channel(topic, SERVICE_CALL)
        else:
            channel = self._json_channel(topic, schema_name_for_topic(topic))
        self._add(channel, log_time_ns, encode_json(data))
        self.derived[topic] = self.derived.get(topic, 0) + 1
        self._derived_total += 1
        if call:
            self.derived_message("call_log", log_time_ns, call_log_message(data, log_time_ns))

    def _add(self, channel: int, log_time_ns: int, data: bytes) -> None:
        self._writer.add_message(channel, log_time_ns, data, log_time_ns, self._sequence)
        self._sequence += 1

    def finish(self) -> None:
        self._writer.finish()


__all__ = ["METADATA_NAME", "RAW_PREFIX", "ImportSink", "raw_topic", "writer_options"]
