"""Open a ROS 1 bag (v2.0; chunks plain, bz2 or lz4) with rosbags, and say precisely
what is wrong with one that cannot be read.

`open_bag(path)` checks the file before rosbags does (exists, a file, not empty, the
`#ROSBAG V2.0` magic, the index inside the file) so the common failures get a clear
one-line `RecordingError` naming the file; whatever rosbags (or a decompressor) raises
later, while reading damaged chunks, is turned into one as well.
"""

from __future__ import annotations

import os
import re
import struct
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType

from rosbags.rosbag1 import Reader
from rosbags.rosbag1.reader import decompressors

from aeroexec.bags.types import ros1_name
from aeroexec.errors import Mark, RecordingError
from aeroexec.inputs import is_regular_file, regular_file
from aeroexec.interrupts import check as check_interrupts

MAGIC = b"#ROSBAG V2.0\n"
_MAGIC_PREFIX = b"#ROSBAG V"
_OP_BAG_HEADER = 3
_COMPRESSION_NAMES = {id(func): name for name, func in decompressors.items()}


def is_ros1_bag(path: str | os.PathLike[str]) -> bool:
    """Does `path` look like a ROS 1 bag (`.bag` name, or the bag magic)? A directory,
    a missing file or an unreadable one counts as a bag when named `.bag`, so that the
    bag reader reports the problem."""
    file = Path(path)
    if file.suffix.lower() == ".bag":
        return True
    if not is_regular_file(file):  # opening a FIFO to look would block
        return False
    try:
        with open(file, "rb") as stream:
            return stream.read(len(_MAGIC_PREFIX)) == _MAGIC_PREFIX
    except OSError:
        return False


@dataclass(frozen=True, slots=True)
class BagConnection:
    """One connection record of the bag (a topic may have several: one per publisher)."""

    id: int
    topic: str
    type: str  # ROS 1 spelling: droneMsgsROS/BehaviorEvent
    msgtype: str  # rosbags' spelling: droneMsgsROS/msg/BehaviorEvent
    msgdef: str = field(repr=False)
    md5sum: str
    callerid: str | None
    latching: int | None
    count: int
    #: How the messages are serialized (`ros1`, or `cdr` for a ROS 2 bag) and how the
    #: definition is written (`ros1msg`, `ros2msg`, `ros2idl`; "" when the bag has none
    #: and aeroexec knows none): the raw channel's message and schema encodings.
    encoding: str = "ros1"
    schema_encoding: str = "ros1msg"
    #: The raw channel's schema name ("" = `type`; ROS 2 keeps `pkg/msg/Name`).
    schema_name: str = ""
    #: More channel metadata (ROS 2: the offered QoS profiles, the type hash, ...).
    extra: tuple[tuple[str, str], ...] = ()


@dataclass(frozen=True, slots=True)
class _Header:
    index_pos: int
    conn_count: int
    chunk_count: int


def _read_header(stream: object, name: str) -> _Header:
    """The bag header record (op 3), with its index position."""
    read = stream.read  # type: ignore[attr-defined]
    raw = read(4)
    if len(raw) < 4:
        raise RecordingError("truncated: the file ends inside the bag header", Mark(name))
    (length,) = struct.unpack("<I", raw)
    body = read(length)
    if len(body) < length:
        raise RecordingError("truncated: the file ends inside the bag header", Mark(name))
    fields: dict[str, bytes] = {}
    pos = 0
    while pos + 4 <= length:
        (size,) = struct.unpack_from("<I", body, pos)
        pos += 4
        key, sep, value = body[pos : pos + size].partition(b"=")
        if not sep or pos + size > length:
            raise RecordingError("damaged bag header record", Mark(name))
        fields[key.decode("ascii", "replace")] = value
        pos += size
    try:
        if fields["op"] != bytes([_OP_BAG_HEADER]):
            raise RecordingError("the first record is not a bag header", Mark(name))
        (index_pos,) = struct.unpack("<Q", fields["index_pos"])
        (conn_count,) = struct.unpack("<I", fields["conn_count"])
        (chunk_count,) = struct.unpack("<I", fields["chunk_count"])
    except (KeyError, struct.error):
        raise RecordingError("damaged bag header record", Mark(name)) from None
    return _Header(index_pos, conn_count, chunk_count)


def _precheck(file: Path, name: str) -> _Header:
    size = regular_file(file, "a ROS 1 bag file", RecordingError)
    try:
        stream = open(file, "rb")  # noqa: SIM115 (closed below)
    except OSError as exc:
        raise RecordingError(f"cannot read: {exc.strerror or exc}", Mark(name)) from None
    with stream:
        if size == 0:
            raise RecordingError("empty file: not a ROS 1 bag", Mark(name))
        magic = stream.read(len(MAGIC))
        if not magic.startswith(_MAGIC_PREFIX):
            raise RecordingError(
                "not a ROS 1 bag (it does not start with '#ROSBAG V2.0')", Mark(name)
            )
        if magic != MAGIC:
            version = magic[len(_MAGIC_PREFIX) :].split(b"\n")[0].decode("ascii", "replace")
            raise RecordingError(
                f"ROS bag format version {version!r} is not supported (only 2.0)", Mark(name)
            )
        header = _read_header(stream, name)
    if header.index_pos == 0:
        raise RecordingError(
            "the bag has no index (its recording was never closed): "
            "run `rosbag reindex` on it first",
            Mark(name),
        )
    if header.index_pos >= size:
        raise RecordingError(
            f"truncated: the bag's index should start at byte {header.index_pos} but the "
            f"file has only {size} bytes (was it cut short? `rosbag reindex` may rescue it)",
            Mark(name),
        )
    return header


class BagFile:
    """An open bag: its connections, chunk facts and a streaming message iterator.
    (`ros2file.Ros2Bag` has the same face for ROS 2 bags.)"""

    ros_version = 1
    format = "2.0"

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        self.name = str(path)
        self.header = _precheck(self.path, self.name)
        self.size = self.path.stat().st_size
        self._reader = Reader(self.path)
        try:
            self._reader.open()
        except Exception as exc:  # rosbags raises ReaderError, struct.error, ...
            raise RecordingError(f"damaged bag: {_reason(exc)}", Mark(self.name)) from None
        reader = self._reader
        self.connections: tuple[BagConnection, ...] = tuple(
            BagConnection(
                c.id,
                c.topic,
                ros1_name(c.msgtype),
                c.msgtype,
                c.msgdef.data,
                c.digest,
                getattr(c.ext, "callerid", None),
                getattr(c.ext, "latching", None),
                c.msgcount,
            )
            for c in reader.connections
        )
        self.message_count = sum(c.count for c in self.connections)
        self.chunk_count = len(reader.chunk_infos)
        self.compression = Counter(
            _COMPRESSION_NAMES.get(id(chunk.decompressor), "?") for chunk in reader.chunks.values()
        )
        if reader.chunk_infos and self.message_count:
            self.start_ns: int | None = reader.start_time
            self.end_ns: int | None = reader.end_time - 1  # rosbags' end is exclusive
        else:
            self.start_ns = self.end_ns = None

    @property
    def compression_text(self) -> str:
        """`none`, `bz2`, `lz4`, or e.g. `lz4 (3 chunks), none (1 chunk)` when mixed."""
        if not self.compression:
            return "none (no chunks)"
        if len(self.compression) == 1:
            return next(iter(self.compression))
        return ", ".join(
            f"{name} ({n} chunk{'s' if n != 1 else ''})"
            for name, n in sorted(self.compression.items())
        )

    def messages(self) -> Iterator[tuple[BagConnection, int, bytes]]:
        """Every message in bag time order: (connection, log time ns, serialized bytes).
        `RecordingError` at the first damaged chunk."""
        by_id = {c.id: c for c in self.connections}
        count = 0
        last = self.start_ns
        try:
            for connection, time_ns, data in self._reader.messages():
                check_interrupts()
                count += 1
                last = time_ns
                yield by_id[connection.id], time_ns, data
        except Exception as exc:  # damaged chunk: ReaderError, OSError (bz2), ...
            where = "in the first chunk"
            if count and last is not None:
                where = f"after {count} messages (bag time {last / 1e9:.3f} s)"
            raise RecordingError(
                f"damaged bag data {where}: {_reason(exc)}", Mark(self.name)
            ) from None

    def close(self) -> None:
        if self._reader.bio is not None:
            self._reader.close()

    def __enter__(self) -> BagFile:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


def _reason(exc: BaseException) -> str:
    """What went wrong, in words: never a bare exception name or a stray number."""
    if isinstance(exc, KeyError):
        # rosbags looks a message's connection (or an index's chunk) up by id
        key = exc.args[0] if exc.args else "?"
        return (
            f"the bag's index and data disagree (a record refers to id {key}, which is not defined)"
        )
    if isinstance(exc, AssertionError) and not str(exc):
        # rosbags asserts that each message is where and when the index says
        return "the bag's index and data disagree (a message is not what the index says)"
    # rosbags nests reasons as "...: ('Header could not be read from file.',)"
    text = _TUPLE_REPR.sub(r"\2", " ".join(str(exc).split()))
    while exc.__cause__ is not None and not text:
        exc = exc.__cause__
        text = " ".join(str(exc).split())
    return text or f"unreadable data ({type(exc).__name__})"


_TUPLE_REPR = re.compile(r"""\((['"])(.*?)\1,\)""")


def open_ros1_bag(path: str | os.PathLike[str]) -> BagFile:
    """Open the ROS 1 bag `path` for reading (`RecordingError`, one line, if it is not
    a readable bag)."""
    return BagFile(path)
