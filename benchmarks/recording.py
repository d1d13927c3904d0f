"""Benchmark: what recording to MCAP costs (issues 17 and 31).

(a) Recording overhead of a simulated mission, recorded vs the same run unrecorded, CPU
    time: the long mission (benchmarks/replay.py's patrol-60: an hour, 65 laps of four
    waypoints and a 40 s hover), the thesis' Appendix C mission and a 10-minute patrol
    (patrol-10: 11 laps). Target: recorded <= 1.5x unrecorded (issue 31: mcap's own
    floor, ~1.3-1.4x, plus 10 %), both
    - in one process (what `simulate` does for `aeroexec run`), and
    - as the whole process minus start-up: `python -m aeroexec run MISSION [--output
      OUT]`, CPU of the child, less the same command on a mission that returns at once
      (interpreter, imports, catalog, session set-up; recorded: the file's header too).
    The floor line beside it: mcap alone writing the very same records (bytes already
    encoded, read back from the recording) and flushing where the recorder flushes,
    added to the unrecorded run: no recorder built on mcap's Python writer can go below.
(b) The recorder's own cost per message: a `Recorder` fed the bus records of a session
    (caught beforehand, so the executive's work is not in it) against mcap alone writing
    the records that recorder wrote, already encoded, flushed at the same points.
    Target <= 1.2x. On the long mission's stream and on the activations' of (c).
(c) Activations through the whole path with recording on, vs the floor: `mcap` alone
    writing the same records (topics, log times, bytes as recorded, already encoded,
    flushed where the recorder flushes). The scripted activations alternate GO_TO_POINT
    and LAND (which preempts it) on the NullVehicle with one executive step after each,
    so every activation goes through the coordinator, specialist and resource manager
    and publishes events and capability changes. Targets: recorded <= 2x the mcap-alone
    cost; recording off >= 50,000 activations/s (one step each).

Every figure is the median of --repeat interleaved rounds (CPU time), on a machine shared
with other work: the figures move by 10-20 % between runs. Prints one line per figure
(figure, baseline, ratio, target); exits 1 when a target is missed.

    .venv/bin/python benchmarks/recording.py [--activations 6000] [--repeat 5]
        [--missions patrol-60,appendix-c,patrol-10]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import statistics
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

from figures import Figure, child_cpu, interleaved, timed
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer
from replay import MISSION, PATROLS, long_endurance_world

from aeroexec.catalog.loader import load_catalog
from aeroexec.catalog.model import Catalog
from aeroexec.catalog.paths import DEFAULT_CATALOG
from aeroexec.executive.behavior import GenericBehavior
from aeroexec.executive.bus import BusObserver, MemoryObserver
from aeroexec.executive.executive import Executive
from aeroexec.executive.messages import ServiceCallRecord, TopicRecord
from aeroexec.mission import APPENDIX_C, SessionConfig, simulate
from aeroexec.recording import FLUSH_BYTES, FLUSH_MESSAGES, Recorder
from aeroexec.recording.schemas import schema_for
from aeroexec.vehicles.null import NullVehicle

MISSION_TARGET = 1.5
RECORDER_TARGET = 1.2
MCAP_TARGET = 2.0
RATE_TARGET = 50_000.0
ROOT = Path(__file__).resolve().parent.parent
#: A mission that returns at once: a whole process's start-up and session set-up.
EMPTY_MISSION = """\
def runMission():
    return True
"""
MISSIONS = ("patrol-60", "appendix-c", "patrol-10")


def mission_inputs(workdir: Path) -> dict[str, tuple[Path, Path | None]]:
    """name -> (mission, world): the patrols in a world whose battery lasts for hours."""
    world = long_endurance_world(workdir)
    inputs: dict[str, tuple[Path, Path | None]] = {"appendix-c": (APPENDIX_C, None)}
    for name in ("patrol-60", "patrol-10"):
        laps, hover = PATROLS[name]
        mission = workdir / f"{name}.py"
        mission.write_text(MISSION.format(laps=laps, hover=hover), encoding="utf-8")
        inputs[name] = (mission, world)
    return inputs


# -- (a) missions --------------------------------------------------------------------------
def _quiet_simulate(config: SessionConfig, observers: list[BusObserver] | None = None) -> None:
    with contextlib.redirect_stdout(io.StringIO()):  # the mission script prints
        simulate(config, observers=observers or [])


Record = tuple[int, str, str, int, bytes]  # (channel id, topic, schema name, log time, data)


def recorded_records(path: Path) -> list[Record]:
    """What the recorder wrote, read back as it is in the file (data still encoded)."""
    records: list[Record] = []
    with open(path, "rb") as stream:
        for schema, channel, message in make_reader(stream).iter_messages(log_time_order=False):
            name = schema.name if schema is not None else ""
            records.append((channel.id, channel.topic, name, message.log_time, message.data))
    return records


def flush_points(records: list[Record]) -> frozenset[int]:
    """After which records a simulated session's recorder closes a chunk (the rule of
    aeroexec/recording/writer.py: FLUSH_MESSAGES messages or FLUSH_BYTES of data,
    whichever first), replayed on the recorded stream."""
    points: set[int] = set()
    pending = size = 0
    for i, (_, _, _, _, data) in enumerate(records):
        pending += 1
        size += len(data)
        if pending >= FLUSH_MESSAGES or size >= FLUSH_BYTES:
            points.add(i)
            pending = size = 0
    return frozenset(points)


def mcap_alone(
    path: Path, records: list[Record], flush_after: frozenset[int] = frozenset()
) -> None:
    """The floor: the same records with the mcap library only (bytes already encoded,
    the recorder's LZ4 and chunk size), with mcap's own `flush()` after `flush_after`
    (the crash-safety bound's chunks)."""
    with open(path, "wb") as stream:
        writer = Writer(stream, chunk_size=FLUSH_BYTES, compression=CompressionType.LZ4)
        writer.start(profile="aeroexec", library="benchmark")
        schemas: dict[str, int] = {}
        channels: dict[int, int] = {}
        add = writer.add_message
        for sequence, (channel_id, topic, schema_name, t, data) in enumerate(records):
            channel = channels.get(channel_id)
            if channel is None:
                schema = schemas.get(schema_name)
                if schema is None:
                    definition = schema_for(schema_name)
                    schema = writer.register_schema(schema_name, "jsonschema", definition.data)
                    schemas[schema_name] = schema
                channel = writer.register_channel(topic, "json", schema)
                channels[channel_id] = channel
            add(channel, t, data, t, sequence)
            if sequence in flush_after:
                writer.flush()
        writer.finish()


def _run_arguments(mission: Path, world: Path | None) -> list[str]:
    return ["run", str(mission), *(["--world", str(world)] if world else []), "-q"]


def _less_start_up(
    command: list[str], start: list[str], root: str, wholes: list[float]
) -> Callable[[], float]:
    """One round: CPU of `command` less that of `start` (its start-up), run right after;
    the whole process's CPU goes to `wholes`."""

    def run() -> float:
        cpu = child_cpu(command, root)
        wholes.append(cpu)
        return cpu - child_cpu(start, root)

    return run


def mission_figures(workdir: Path, repeat: int, root: Path, names: list[str]) -> list[Figure]:
    inputs = mission_inputs(workdir)
    empty = workdir / "empty.py"
    empty.write_text(EMPTY_MISSION, encoding="utf-8")
    figures: list[Figure] = []
    for name in names:
        mission, world = inputs[name]
        plain = SessionConfig(mission=mission, world=world)
        out = workdir / f"{name}.mcap"
        recorded = SessionConfig(mission=mission, world=world, record=out)
        _quiet_simulate(plain)  # also the warm-up: imports, caches
        _quiet_simulate(recorded)
        records = recorded_records(out)
        points = flush_points(records)
        alone = workdir / f"{name}-alone.mcap"
        python = [sys.executable, "-m", "aeroexec"]
        run = [*python, *_run_arguments(mission, world)]
        start = [*python, *_run_arguments(empty, world)]
        whole_out = workdir / f"{name}-whole.mcap"
        start_out = workdir / f"{name}-start.mcap"
        medians = interleaved(
            {
                "off": timed(lambda plain=plain: _quiet_simulate(plain)),
                "on": timed(lambda recorded=recorded: _quiet_simulate(recorded)),
                "mcap": timed(
                    lambda records=records, alone=alone, points=points: mcap_alone(
                        alone, records, points
                    )
                ),
            },
            repeat,
        )
        # Whole processes: each round's figure is the process less its own start-up,
        # run right after it (a difference of two ~0.4 s processes: pairing them keeps
        # the machine's drift out of it); a mission under 0.5 s gets three times the rounds.
        whole: dict[str, list[float]] = {"off": [], "on": []}
        output = ["--output", str(whole_out)]
        start_output = ["--output", str(start_out)]
        processes = interleaved(
            {
                "off": _less_start_up(run, start, str(root), whole["off"]),
                "on": _less_start_up(
                    [*run, *output], [*start, *start_output], str(root), whole["on"]
                ),
            },
            repeat if medians["off"] > 0.5 else 3 * repeat,
        )
        label = f"{name} ({len(records):,} messages)"
        figures += [
            Figure(
                f"(a) {label}, recorded, one process",
                medians["on"],
                medians["off"],
                "unrecorded",
                MISSION_TARGET,
            ),
            Figure(
                "    floor: unrecorded + mcap alone writing the same encoded records, "
                "flushed where the recorder flushes",
                medians["off"] + medians["mcap"],
                medians["off"],
                "unrecorded",
                MISSION_TARGET,
            ),
            Figure(
                f"    whole process minus start-up: aeroexec run --output ({name})",
                processes["on"],
                processes["off"],
                "aeroexec run",
                MISSION_TARGET,
            ),
            Figure(
                "    for scale: whole process with start-up",
                statistics.median(whole["on"]),
                statistics.median(whole["off"]),
                "aeroexec run",
                MISSION_TARGET,
            ),
        ]
    return figures


# -- (b) the recorder alone ----------------------------------------------------------------
BusRecord = ServiceCallRecord | TopicRecord


def feed(path: Path, stream: list[BusRecord], start_pose: tuple[float, ...] | None) -> None:
    """A `Recorder` writing a session's bus records (what it does in the session)."""
    pose = (0.0, 0.0, 0.0, 0.0) if start_pose is None else start_pose
    with Recorder(path, start_pose=pose) as recorder:  # type: ignore[arg-type]
        calls, topics = recorder.on_service_call, recorder.on_topic
        for record in stream:
            if type(record) is ServiceCallRecord:
                calls(record)
            else:
                topics(record)  # type: ignore[arg-type]


def recorder_figure(
    workdir: Path, name: str, run: Callable[[list[BusObserver]], None], repeat: int
) -> Figure:
    memory = MemoryObserver()
    run([memory])
    stream = memory.records
    out, alone = workdir / f"{name}-fed.mcap", workdir / f"{name}-fed-alone.mcap"
    feed(out, stream, None)
    records = recorded_records(out)
    points = flush_points(records)
    medians = interleaved(
        {
            "recorder": timed(lambda: feed(out, stream, None)),
            "mcap": timed(lambda: mcap_alone(alone, records, points)),
        },
        repeat,
    )
    n = len(records)
    return Figure(
        f"(b) the recorder's cost per message, {name}'s bus records ({n:,} messages, "
        f"{medians['recorder'] / n * 1e6:.1f} vs {medians['mcap'] / n * 1e6:.1f} us)",
        medians["recorder"],
        medians["mcap"],
        "mcap alone, same encoded records",
        RECORDER_TARGET,
    )


# -- (c) activations -----------------------------------------------------------------------
def drive(catalog: Catalog, activations: int, observers: list[BusObserver]) -> None:
    executive = Executive(
        catalog, vehicle=NullVehicle(), library={}, stand_in=GenericBehavior, observers=observers
    )
    for i in range(activations // 2):
        executive.activate_behavior("GO_TO_POINT", {"coordinates": [i % 50, 1.0, 2.0]})
        executive.step()
        executive.activate_behavior("LAND")
        executive.step()


def activation_figures(workdir: Path, activations: int, repeat: int) -> list[Figure]:
    catalog = load_catalog(DEFAULT_CATALOG)
    out = workdir / "activations.mcap"
    alone = workdir / "alone.mcap"

    def recorded() -> None:
        with Recorder(out) as recorder:
            drive(catalog, activations, [recorder])

    recorded()
    records = recorded_records(out)
    points = flush_points(records)
    medians = interleaved(
        {
            "off": timed(lambda: drive(catalog, activations, [])),
            "on": timed(recorded),
            "mcap": timed(lambda: mcap_alone(alone, records, points)),
        },
        repeat,
    )
    n = activations
    return [
        Figure(
            f"(c) {n:,} activations + steps, recording on ({len(records):,} messages)",
            medians["on"],
            medians["mcap"],
            "mcap alone, same encoded records",
            MCAP_TARGET,
        ),
        Figure(
            "(c) activations/s, recording off, one executive step each",
            n / medians["off"],
            n / medians["on"],
            "recording on",
            RATE_TARGET,
            unit="/s",
            kind="min",
        ),
    ]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--activations", type=int, default=6_000)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--missions", default=",".join(MISSIONS), help="which of (a)")
    parser.add_argument(
        "--root", type=Path, default=ROOT, help="the checkout whole processes run (`python -m`)"
    )
    args = parser.parse_args(argv)
    names = [n for n in args.missions.split(",") if n]
    unknown = sorted(set(names) - set(MISSIONS))
    if unknown:
        parser.error(f"unknown mission {', '.join(unknown)} (one of {', '.join(MISSIONS)})")
    catalog = load_catalog(DEFAULT_CATALOG)
    with tempfile.TemporaryDirectory() as tmp:
        workdir = Path(tmp)
        figures = mission_figures(workdir, args.repeat, args.root, names)
        mission, world = mission_inputs(workdir)["patrol-60"]
        long_mission = SessionConfig(mission=mission, world=world)
        figures += [
            recorder_figure(
                workdir,
                "patrol-60",
                lambda observers: _quiet_simulate(long_mission, observers),
                args.repeat,
            ),
            recorder_figure(
                workdir,
                "activations",
                lambda observers: drive(catalog, args.activations, observers),
                args.repeat,
            ),
        ]
        figures += activation_figures(workdir, args.activations, args.repeat)
    print(f"recording, CPU time, median of {args.repeat} interleaved rounds (shared machine)")
    for figure in figures:
        print(figure.line())
    targets = [f for f in figures if "floor" not in f.name and "for scale" not in f.name]
    return 0 if all(f.ok for f in targets) else 1


if __name__ == "__main__":
    sys.exit(main())
