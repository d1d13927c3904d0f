"""`write_view`: one or two aeroexec recordings into one Rerun `.rrd` file.

    report = write_view(["flight.mcap"], "flight.rrd")
    report = write_view(["base.mcap", "replay.mcap"], "diff.rrd")   # under /base and /new
    report = write_view(["flight.bag"], "flight.rrd")    # a ROS 1 bag, imported on the way

Each input is checked first (readable MCAP, aeroexec profile, at least one message), so
nothing is written for a bad input. A ROS 1 bag is imported (aeroexec.bags, the shipped
Aerostack mapping) into a temporary recording, removed afterwards; the view names the
bag. The output holds one Rerun recording, application
`aeroexec`, whose recording id is derived from the inputs' contents (the same inputs give
the same id), with the blueprint of blueprint.py as its default layout. Only a recording
stream created here is used, never Rerun's global one.
"""

from __future__ import annotations

import hashlib
import os
import uuid
from collections.abc import Iterator, Sequence
from contextlib import AbstractContextManager, ExitStack, contextmanager, nullcontext
from dataclasses import dataclass
from pathlib import Path

import rerun as rr

from aeroexec.errors import Mark, RecordingError
from aeroexec.outputs import Pipe, whole_file_or_none
from aeroexec.progress import Advance, ProgressFactory
from aeroexec.recording.reader import Recording, open_recording
from aeroexec.recording.schemas import MESSAGE_ENCODING, PROFILE
from aeroexec.vehicles.world import World
from aeroexec.viz.blueprint import build_blueprint
from aeroexec.viz.columns import ColumnWriter
from aeroexec.viz.convert import PROGRESS_EVERY, ConvertStats, SessionConverter, session_origin_ns
from aeroexec.viz.layout import Layout, layouts_for
from aeroexec.viz.scene import (
    log_vehicle_body,
    log_view_coordinates,
    log_world,
    recorded_world,
    trajectory_color,
)

APPLICATION_ID = "aeroexec"
RRD_SUFFIX = ".rrd"


@dataclass(frozen=True, slots=True)
class SourceReport:
    file: str
    root: str
    complete: bool
    problem: str | None
    messages: int
    stats: ConvertStats
    notes: tuple[str, ...]


@dataclass(frozen=True, slots=True)
class ViewReport:
    output: Path
    recording_id: str
    sources: tuple[SourceReport, ...]


def default_output(recording: str | os.PathLike[str]) -> Path:
    """`<REC stem>.rrd` next to the recording."""
    return Path(recording).with_suffix(RRD_SUFFIX)


@dataclass(frozen=True, slots=True)
class _Source:
    """An input as shown (`name`: what the user gave) and the recording read for it."""

    name: str
    recording: Recording
    notes: tuple[str, ...] = ()
    #: An imported bag: its raw ROS 1 channels are not decoded, by design (no note).
    raw_kept: bool = False


@contextmanager
def _opened(path: Path) -> Iterator[_Source]:
    """The recording of `path`: itself, or for a ROS 1 or ROS 2 bag a temporary import."""
    from aeroexec.bags.source import is_bag

    if not is_bag(path):
        yield _Source(str(path), open_session(path))
        return
    from aeroexec.bags.replay import bag_recording

    with bag_recording(path) as imported:
        if not imported.report.derived:
            mapping = "Aerostack" if imported.report.ros_version == 1 else "Aerostack2"
            raise RecordingError(
                f"nothing to show: the bag has none of the topics the {mapping} mapping knows "
                "(poses, behavior and resource topics); `aeroexec import --mapping` then view "
                "the .mcap",
                Mark(str(path)),
            )
        notes = tuple(f"imported from the bag: {note}" for note in imported.report.notes)
        recording = open_session(imported.path, shown_as=str(path))
        yield _Source(str(path), recording, notes, raw_kept=True)


def open_session(path: str | os.PathLike[str], *, shown_as: str | None = None) -> Recording:
    """Open an aeroexec recording to view; `RecordingError` (one line) for anything else
    (naming `shown_as` when given: the bag a temporary recording came from)."""
    recording = open_recording(path)
    where = Mark(shown_as or str(path))
    if recording.profile != PROFILE:
        profile = recording.profile or "none"
        raise RecordingError(
            f"not an aeroexec recording (profile {profile}); `aeroexec info` lists its channels",
            where,
        )
    survey = recording.survey()
    if survey.message_count == 0:
        why = f": {survey.end.problem}" if survey.end.problem else ""
        raise RecordingError(f"no messages could be read{why}", where)
    return recording


def recording_id_for(paths: Sequence[str | os.PathLike[str]]) -> str:
    """A UUID derived from the inputs' bytes (and their order; a ROS 2 bag directory:
    its files' names and bytes, in name order)."""
    digest = hashlib.sha256(b"aeroexec view\0")
    for path in paths:
        file_hash = hashlib.sha256()
        folder = Path(path)
        files = sorted(p for p in folder.rglob("*") if p.is_file()) if folder.is_dir() else [folder]
        for file in files:
            if file is not folder:
                file_hash.update(str(file.relative_to(folder)).encode() + b"\0")
            with open(file, "rb") as f:
                for block in iter(lambda f=f: f.read(1 << 20), b""):
                    file_hash.update(block)
        digest.update(file_hash.digest())
    return str(uuid.UUID(bytes=digest.digest()[:16], version=4))


def _check_output(output: Path, inputs: Sequence[Path]) -> None:
    where = Mark(str(output))
    if output.is_dir():
        raise RecordingError("is a directory; give a file name ending in .rrd", where)
    parent = output.parent if str(output.parent) else Path(".")
    if not parent.is_dir():
        raise RecordingError(f"cannot write: no directory {parent}", where)
    if not os.access(parent, os.W_OK):
        raise RecordingError(f"cannot write: directory {parent} is not writable", where)
    for source in inputs:
        if output.exists() and source.exists() and output.samefile(source):
            raise RecordingError("would overwrite its own input", where)


def _no_progress(description: str, total: int) -> AbstractContextManager[Advance]:
    return nullcontext(lambda n: None)


def write_view(
    recordings: Sequence[str | os.PathLike[str]],
    output: str | os.PathLike[str],
    *,
    progress: ProgressFactory | None = None,
) -> ViewReport:
    """Convert one recording, or two side by side, into the `.rrd` file `output`; a ROS 1
    bag is imported into a temporary recording first."""
    inputs = [Path(p) for p in recordings]
    with ExitStack() as stack:
        sources = [stack.enter_context(_opened(p)) for p in inputs]
        return _write(sources, inputs, Path(output), progress or _no_progress)


def _write(
    sources: list[_Source], inputs: list[Path], out: Path, progress: ProgressFactory
) -> ViewReport:
    _check_output(out, inputs)
    labels = [Path(source.name).name for source in sources]
    layouts = layouts_for(labels)
    recording_id = recording_id_for(inputs)

    if os.environ.get("RERUN", "").strip().lower() in ("0", "no", "off", "false"):
        # a disabled stream would write an empty file
        raise RecordingError("Rerun logging is disabled (RERUN=off in the environment)")
    stream = rr.RecordingStream(APPLICATION_ID, recording_id=recording_id, send_properties=False)
    stream.set_log_time_enabled(False)  # no wall-clock timeline: same input, same rows
    stream.set_log_tick_enabled(False)
    reports = []
    # Written beside `out` and renamed into place when complete: a full disk or a signal
    # leaves no partial .rrd behind.
    with whole_file_or_none(out) as temp:
        # Rerun writes into a FIFO that a thread copies to `temp`: its file sink can
        # deadlock when a write fails under it (a full disk); ours reports the error.
        pipe = Pipe(temp)
        try:
            stream.save(str(pipe.path), default_blueprint=build_blueprint(layouts))
            stream.send_recording_name(" vs ".join(labels))
            log_view_coordinates(stream)
            writer = ColumnWriter(stream)
            for index, (source, layout) in enumerate(zip(sources, layouts, strict=True)):
                recording = source.recording
                stats = _convert(stream, writer, source, layout, index, progress)
                survey = recording.survey()
                notes = [
                    *source.notes,
                    *stats.notes,
                    *([] if source.raw_kept else recording.notes),
                ]
                reports.append(
                    SourceReport(
                        file=source.name,
                        root=layout.origin,
                        complete=survey.end.complete,
                        problem=survey.end.problem,
                        messages=survey.message_count,
                        stats=stats,
                        notes=tuple(notes),
                    )
                )
            stream.flush()
        finally:
            stream.disconnect()  # closes the FIFO: the copy ends
            pipe.finish()  # raises the copy's write error, if any
    return ViewReport(out, recording_id, tuple(reports))


def start_source(
    stream: rr.RecordingStream,
    layout: Layout,
    facts: dict[str, str],
    world: World | None,
    color: tuple[int, int, int],
) -> None:
    """What a source shows before its first message (here and in the live view): the
    session's metadata (seed, catalog, world, ...) as a recording property, the world's
    markers and the vehicle's body."""
    stream.send_property(layout.root or "session", rr.AnyValues(**facts))
    if world is not None:
        log_world(stream, layout, world)
    log_vehicle_body(stream, layout, color)


def _convert(
    stream: rr.RecordingStream,
    writer: ColumnWriter,
    source: _Source,
    layout: Layout,
    index: int,
    progress: ProgressFactory,
) -> ConvertStats:
    recording = source.recording
    color = trajectory_color(index)
    facts = {"file": Path(source.name).name, **recording.metadata.get("aeroexec", {})}
    world, world_note = recorded_world(recording)
    start_source(stream, layout, facts, world, color)
    survey = recording.survey()
    converter = SessionConverter(
        stream, writer, layout, origin_ns=session_origin_ns(recording), world=world, color=color
    )
    # The bar counts what the pass decodes: the JSON messages (an imported bag's raw
    # ros1 channels are read past, not converted).
    decoded = sum(
        count
        for cid, count in survey.counts.items()
        if cid in survey.channels and survey.channels[cid].message_encoding == MESSAGE_ENCODING
    )
    with progress(source.name, decoded) as advance:
        count = 0
        for record in recording.records():
            converter.feed(record)
            count += 1
            if count % PROGRESS_EVERY == 0:
                advance(PROGRESS_EVERY)
        advance(count % PROGRESS_EVERY)
    stats = converter.finish()
    if world_note:
        stats.notes.append(world_note)
    return stats
