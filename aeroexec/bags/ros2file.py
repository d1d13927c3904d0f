"""Open a ROS 2 bag (rosbag2: a directory with its `metadata.yaml`, a bare `.mcap` or a
bare `.db3`) with rosbags, with the same face as `bagfile.BagFile`: connections,
facts, and a streaming, time-ordered message iterator of the serialized (CDR) bytes.

Each connection leaves here with a definition Foxglove can decode its raw channel with:
the bag's own (`ros2msg` or `ros2idl`), or, for service events and bags without
definitions, the one `ros2types.Ros2Types` completes (the bag's own text is then kept
in the channel metadata as `bag_definition`).
"""

from __future__ import annotations

import os
import sqlite3
import struct
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from types import TracebackType

from mcap.reader import make_reader
from rosbags.interfaces import Connection, ConnectionExtRosbag2, MessageDefinitionFormat
from rosbags.rosbag2 import Reader
from rosbags.rosbag2.metadata import dump_qos_v8

from aeroexec.bags.bagfile import BagConnection, _reason
from aeroexec.bags.ros2types import Ros2Types, is_interface_text
from aeroexec.bags.types import ros1_name
from aeroexec.errors import Mark, RecordingError
from aeroexec.inputs import is_directory, is_regular_file
from aeroexec.interrupts import check as check_interrupts

MCAP_MAGIC = b"\x89MCAP0\r\n"
_SUFFIXES = (".mcap", ".db3")
_FORMATS = {MessageDefinitionFormat.MSG: "ros2msg", MessageDefinitionFormat.IDL: "ros2idl"}


def mcap_profile(path: Path) -> str | None:
    """The profile in an MCAP file's header (`ros2`, `aeroexec`, ...), None when the file
    is not an MCAP file (or cannot be read)."""
    try:
        with open(path, "rb") as stream:
            head = stream.read(len(MCAP_MAGIC) + 9 + 4)
            if not head.startswith(MCAP_MAGIC) or len(head) < len(MCAP_MAGIC) + 13:
                return None
            (size,) = struct.unpack_from("<I", head, len(MCAP_MAGIC) + 9)
            return stream.read(min(size, 256)).decode("utf-8", "replace")
    except OSError:
        return None


def is_ros2_bag(path: str | os.PathLike[str]) -> bool:
    """A rosbag2 directory (with metadata.yaml), a `.db3` file, or an MCAP file whose
    profile is `ros2`."""
    file = Path(path)
    # Neither asks Path.is_dir/is_file, which raise where a parent cannot be searched:
    # the reader says why in its one line.
    if is_directory(file):
        return is_regular_file(file / "metadata.yaml")
    if file.suffix.lower() == ".db3":
        return True
    return file.suffix.lower() == ".mcap" and is_regular_file(file) and mcap_profile(file) == "ros2"


class Ros2Bag:
    """An open ROS 2 bag (see the module docstring)."""

    ros_version = 2

    def __init__(self, path: str | os.PathLike[str], types: Ros2Types | None = None) -> None:
        self.path = Path(path)
        self.name = str(path)
        self.types = types if types is not None else Ros2Types()
        #: What was completed or could not be (the import's notes).
        self.notes: list[str] = []
        self._check()
        try:
            self._reader = Reader(self.path)
            self._reader.open()
        except RecordingError:
            raise
        except Exception as exc:  # ReaderError, FileNotFoundError, sqlite3 errors, ...
            raise RecordingError(
                f"not a readable ROS 2 bag: {_reason(exc)}", Mark(self.name)
            ) from None
        reader = self._reader
        self.storage = "sqlite3" if self._storage_files(".db3") else "mcap"
        self.format = f"rosbag2 {self.storage}"
        self.distro = reader.ros_distro or ""
        files = [self.path] if self.path.is_file() else sorted(self.path.iterdir())
        self.size = sum(f.stat().st_size for f in files if f.is_file())
        services = self._service_texts()
        self.connections: tuple[BagConnection, ...] = tuple(
            self._connection(c, services) for c in reader.connections
        )
        self.message_count = sum(c.count for c in self.connections)
        self.compression, self.chunk_count = self._compression()
        if self.message_count:
            self.start_ns: int | None = reader.start_time
            self.end_ns: int | None = reader.end_time - 1  # rosbags' end is exclusive
        else:
            self.start_ns = self.end_ns = None

    # -- opening -----------------------------------------------------------------------------
    def _check(self) -> None:
        file = self.path
        if not file.exists():
            raise RecordingError("no such file or directory", Mark(self.name))
        if file.is_dir():
            if not (file / "metadata.yaml").is_file():
                raise RecordingError(
                    "a directory, but not a rosbag2 bag (it has no metadata.yaml)", Mark(self.name)
                )
            return
        if not file.is_file():
            raise RecordingError("not a regular file", Mark(self.name))
        if file.suffix.lower() not in _SUFFIXES:
            raise RecordingError(
                "not a ROS 2 bag (a rosbag2 directory, a .mcap or a .db3 file)", Mark(self.name)
            )
        if file.stat().st_size == 0:
            raise RecordingError("empty file: not a ROS 2 bag", Mark(self.name))
        if file.suffix.lower() == ".mcap":
            profile = mcap_profile(file)
            if profile is None:
                raise RecordingError("not an MCAP file (no MCAP magic)", Mark(self.name))
            if profile == "aeroexec":
                raise RecordingError(
                    "already an aeroexec recording, not a ROS 2 bag", Mark(self.name)
                )

    def _storage_files(self, suffix: str) -> list[Path]:
        if self.path.is_file():
            return [self.path] if self.path.suffix.lower() == suffix else []
        return sorted(p for p in self.path.iterdir() if p.suffix.lower() == suffix)

    def _service_texts(self) -> dict[str, str]:
        """sqlite3 storage keeps a service's `.srv` text under `<pkg>/srv/<Name>` in its
        `message_definitions` table, and rosbags gives its `_Event` topic none."""
        texts: dict[str, str] = {}
        for db3 in self._storage_files(".db3"):
            try:
                with sqlite3.connect(f"file:{db3}?mode=ro", uri=True) as db:
                    rows = db.execute(
                        "SELECT topic_type, encoded_message_definition FROM message_definitions"
                    ).fetchall()
            except sqlite3.Error:  # schema before 4: no definitions at all
                continue
            for type_name, text in rows:
                if ("/srv/" in type_name or "/action/" in type_name) and text:
                    texts.setdefault(type_name, text)
        return texts

    def _connection(self, c: Connection, services: dict[str, str]) -> BagConnection:
        msgtype = c.msgtype
        msgdef = c.msgdef
        text = msgdef.data
        encoding = _FORMATS.get(msgdef.format, "")
        extra: list[tuple[str, str]] = []
        is_event = msgtype.endswith("_Event") and ("/srv/" in msgtype or "/action/" in msgtype)
        if is_event and not text.strip():
            text = services.get(msgtype[: -len("_Event")], "") or services.get(
                msgtype.rsplit("_", 2)[0],
                "",  # an action's: <pkg>/action/<Name>
            )
            encoding = "ros2msg" if text else ""
        if is_event and encoding == "ros2msg" and is_interface_text(text):
            try:
                fixed = self.types.service_event_definition(msgtype, text)
            except ValueError as exc:
                self.notes.append(f"{c.topic}: the service definition cannot be used: {exc}")
            else:
                extra.append(("bag_definition", text))
                text = fixed
        elif not encoding:
            generated = self.types.definition(msgtype)
            if generated is not None:
                text, encoding = generated, "ros2msg"
                extra.append(("definition_from", self.types.origin(msgtype)))
            else:
                self.notes.append(
                    f"{c.topic}: the bag has no definition of {msgtype} and aeroexec knows "
                    "none (--types DIR): its raw channel has no schema"
                )
        ext = c.ext
        assert isinstance(ext, ConnectionExtRosbag2)
        qos = ext.offered_qos_profiles
        if qos:
            extra.append(("offered_qos_profiles", dump_qos_v8(qos)))
        if c.digest:
            extra.append(("topic_type_hash", c.digest))
        return BagConnection(
            id=c.id,
            topic=c.topic,
            type=ros1_name(msgtype),
            msgtype=msgtype,
            msgdef=text,
            md5sum="",
            callerid=None,
            latching=None,
            count=c.msgcount,
            encoding=ext.serialization_format,
            schema_encoding=encoding,
            schema_name=msgtype,
            extra=tuple(extra),
        )

    def _compression(self) -> tuple[Counter[str], int]:
        """Chunk compressions of the MCAP storage files (rosbag2's own file/message zstd
        otherwise), and the number of chunks."""
        mode = self._reader.compression_mode
        if mode:
            return Counter({f"{self._reader.compression_format} ({mode})": 1}), 0
        counts: Counter[str] = Counter()
        for file in self._storage_files(".mcap"):
            try:
                with open(file, "rb") as stream:
                    summary = make_reader(stream).get_summary()
            except Exception:  # a file without summary: counted by the scan, not here
                continue
            for chunk in summary.chunk_indexes if summary else []:
                counts[chunk.compression or "none"] += 1
        return counts, sum(counts.values())

    @property
    def compression_text(self) -> str:
        if not self.compression:
            return "none (sqlite3)" if self.storage == "sqlite3" else "none (no chunks)"
        if len(self.compression) == 1:
            return next(iter(self.compression))
        return ", ".join(f"{name} ({n} chunks)" for name, n in sorted(self.compression.items()))

    # -- reading -----------------------------------------------------------------------------
    def messages(self) -> Iterator[tuple[BagConnection, int, bytes]]:
        """Every message in time order: (connection, log time ns, CDR bytes)."""
        by_id = {c.id: c for c in self.connections}
        count = 0
        last = self.start_ns
        try:
            for connection, time_ns, data in self._reader.messages():
                check_interrupts()
                count += 1
                last = time_ns
                # rosbags gives bytes (a copy only for another buffer type)
                yield by_id[connection.id], time_ns, data if type(data) is bytes else bytes(data)
        except RecordingError:
            raise
        except Exception as exc:
            where = "before the first message"
            if count and last is not None:
                where = f"after {count} messages (bag time {last / 1e9:.3f} s)"
            raise RecordingError(
                f"damaged bag data {where}: {_reason(exc)}", Mark(self.name)
            ) from None

    def close(self) -> None:
        if getattr(self, "_reader", None) is not None and self._reader.is_open:
            self._reader.close()

    def __enter__(self) -> Ros2Bag:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()
