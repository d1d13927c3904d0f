"""Benchmark: what recording to MCAP costs (issue 17).

(a) Recording overhead of a simulated mission, in one process (what `simulate` does for
    `aeroexec run`), recorded vs the same run unrecorded, CPU time: the thesis' Appendix C
    mission and a 10-minute patrol (benchmarks/replay.py's patrol-10: take off, 11 laps
    of four waypoints and a 40 s hover, land). Target: recorded <= 1.3x unrecorded. The
    floor line beside it: `mcap` alone writing the very same records (bytes already
    encoded, read back from the recording) with its default chunking, added to the
    unrecorded run: no recorder built on mcap's Python writer can go below it.
    Whole-process variant: `python -m aeroexec run MISSION [--output OUT]`, CPU of the
    child, start-up included (what a user feels).
(b) Activations through the whole path with recording on, vs the floor: `mcap` alone
    writing the same records (topics, log times, bytes as recorded, already encoded).
    The scripted activations alternate GO_TO_POINT and LAND (which preempts it) on the
    NullVehicle with one executive step after each, so every activation goes through
    the coordinator, specialist and resource manager and publishes events and capability
    changes. Targets: recorded <= 2x the mcap-alone cost; recording off >= 50,000
    activations/s (one step each).

Every figure is the median of --repeat interleaved rounds (CPU time), on a machine shared
with other work: the figures move by 10-20 % between runs. Prints one line per figure
(figure, baseline, ratio, target); exits 1 when a target is missed.

    .venv/bin/python benchmarks/recording.py [--activations 6000] [--repeat 7]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
import tempfile
from pathlib import Path

from figures import Figure, child_cpu, interleaved, timed
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer

from aeroexec.catalog.loader import load_catalog
from aeroexec.catalog.model import Catalog
from aeroexec.catalog.paths import DEFAULT_CATALOG
from aeroexec.executive.behavior import GenericBehavior
from aeroexec.executive.bus import BusObserver
from aeroexec.executive.executive import Executive
from aeroexec.mission import APPENDIX_C, SessionConfig, simulate
from aeroexec.recording import Recorder
from aeroexec.recording.schemas import schema_for
from aeroexec.recording.writer import FLUSH_INTERVAL_NS, FLUSH_MESSAGES
from aeroexec.vehicles.null import NullVehicle
from aeroexec.vehicles.world import DEFAULT_WORLD

MISSION_TARGET = 1.3
MCAP_TARGET = 2.0
RATE_TARGET = 50_000.0
ROOT = Path(__file__).resolve().parent.parent
PATROL = """\
import executive_engine_api as api


def runMission():
    api.executeBehavior("TAKE_OFF")
    for lap in range(11):
        for point in ([3, 0, 1.5], [3, 3, 1.5], [0, 3, 1.5], [0, 0, 1.5]):
            api.executeBehavior("GO_TO_POINT", coordinates=point)
        api.executeBehavior("KEEP_HOVERING", duration=40)
    api.executeBehavior("LAND")
    return True
"""
#: The patrol's world: the default one with a battery that lasts the 10 minutes.
ENDURANCE = (("flight_endurance: 1200", "flight_endurance: 36000"),)


def patrol_inputs(workdir: Path) -> tuple[Path, Path]:
    text = DEFAULT_WORLD.read_text(encoding="utf-8")
    for old, new in ENDURANCE:
        text = text.replace(old, new)
    world = workdir / "endurance.yaml"
    world.write_text(text, encoding="utf-8")
    mission = workdir / "patrol.py"
    mission.write_text(PATROL, encoding="utf-8")
    return mission, world


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
    """After which records the recorder's flush bound closes a chunk (the rule of
    aeroexec/recording/writer.py: FLUSH_MESSAGES messages or FLUSH_INTERVAL_NS of clock
    time, whichever first), replayed on the recorded log times."""
    points: set[int] = set()
    pending, since = 0, 0
    for i, (_, _, _, t, _) in enumerate(records):
        if not pending:
            since = t
        pending += 1
        if pending >= FLUSH_MESSAGES or t - since >= FLUSH_INTERVAL_NS:
            points.add(i)
            pending = 0
    return frozenset(points)


def mcap_alone(
    path: Path, records: list[Record], flush_after: frozenset[int] = frozenset()
) -> None:
    """The floor: the same records with the mcap library only (bytes already encoded,
    the recorder's LZ4, mcap's default chunk size). With `flush_after`: mcap's own
    `flush()` after those records too (the crash-safety bound's chunks)."""
    with open(path, "wb") as stream:
        writer = Writer(stream, compression=CompressionType.LZ4)
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


def mission_figures(workdir: Path, repeat: int, root: Path) -> list[Figure]:
    mission, world = patrol_inputs(workdir)
    cases = {
        "Appendix C": (SessionConfig(mission=APPENDIX_C), ["run", str(APPENDIX_C)]),
        "patrol-10": (
            SessionConfig(mission=mission, world=world),
            ["run", str(mission), "--world", str(world)],
        ),
    }
    figures: list[Figure] = []
    for name, (plain, arguments) in cases.items():
        out = workdir / f"{name}.mcap"
        recorded = SessionConfig(**{**plain.__dict__, "record": out})
        _quiet_simulate(plain)  # also the warm-up: imports, caches
        _quiet_simulate(recorded)
        records = recorded_records(out)
        points = flush_points(records)
        alone = workdir / f"{name}-alone.mcap"
        python = [sys.executable, "-m", "aeroexec", *arguments, "-q"]
        whole_out = workdir / f"{name}-whole.mcap"
        medians = interleaved(
            {
                "off": timed(lambda plain=plain: _quiet_simulate(plain)),
                "on": timed(lambda recorded=recorded: _quiet_simulate(recorded)),
                "mcap": timed(lambda records=records, alone=alone: mcap_alone(alone, records)),
                "mcap flushed": timed(
                    lambda records=records, alone=alone, points=points: mcap_alone(
                        alone, records, points
                    )
                ),
                "process off": lambda python=python: child_cpu(python, str(root)),
                "process on": lambda python=python, whole_out=whole_out: child_cpu(
                    [*python, "--output", str(whole_out)], str(root)
                ),
            },
            repeat,
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
                "    floor: unrecorded + mcap alone writing the same encoded records",
                medians["off"] + medians["mcap"],
                medians["off"],
                "unrecorded",
                MISSION_TARGET,
            ),
            Figure(
                "    floor with the flush bound: unrecorded + mcap alone, flushed where the "
                "recorder flushes",
                medians["off"] + medians["mcap flushed"],
                medians["off"],
                "unrecorded",
                MISSION_TARGET,
            ),
            Figure(
                f"    whole process: aeroexec run --output ({name})",
                medians["process on"],
                medians["process off"],
                "aeroexec run",
                MISSION_TARGET,
            ),
        ]
    return figures


# -- (b) activations -----------------------------------------------------------------------
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
            "mcap": timed(lambda: mcap_alone(alone, records)),
            "mcap flushed": timed(lambda: mcap_alone(alone, records, points)),
        },
        repeat,
    )
    n = activations
    return [
        Figure(
            f"(b) {n:,} activations + steps, recording on ({len(records):,} messages)",
            medians["on"],
            medians["mcap"],
            "mcap alone, same encoded records",
            MCAP_TARGET,
        ),
        Figure(
            "    for scale: mcap alone, flushed where the recorder flushes",
            medians["mcap flushed"],
            medians["mcap"],
            "mcap alone, same encoded records",
            MCAP_TARGET,
        ),
        Figure(
            "(b) activations/s, recording off, one executive step each",
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
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument(
        "--root", type=Path, default=ROOT, help="the checkout whole processes run (`python -m`)"
    )
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        workdir = Path(tmp)
        figures = mission_figures(workdir, args.repeat, args.root)
        figures += activation_figures(workdir, args.activations, args.repeat)
    print(f"recording, CPU time, median of {args.repeat} interleaved rounds (shared machine)")
    for figure in figures:
        print(figure.line())
    targets = [f for f in figures if "floor" not in f.name and "for scale" not in f.name]
    return 0 if all(f.ok for f in targets) else 1


if __name__ == "__main__":
    sys.exit(main())
