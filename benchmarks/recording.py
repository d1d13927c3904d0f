"""Benchmark: what recording to MCAP costs (design.md section 10).

(a) Recording overhead on a simulated mission: the thesis' Appendix C mission through
    `aeroexec.mission.simulate` (what `aeroexec run` does), with `--record` vs without.
    Target: recorded <= 1.3x the same run unrecorded.
(b) Activations through the whole path with recording on, vs writing the very same
    messages (same topics, log times and payloads, JSON-encoded) with the `mcap` library
    alone. The scripted activations alternate GO_TO_POINT and LAND (which preempts it) on
    the NullVehicle with one executive step after each, so every activation goes through
    the coordinator, specialist and resource manager and publishes events and capability
    changes. Target: recorded cost <= 3x the mcap-alone cost.

Each figure is the best of --repeat runs (interleaved; the short mission gets 4x as
many), measured in one process. Prints
the figures and targets; exits 1 when a target is missed.

    .venv/bin/python benchmarks/recording.py [--activations 6000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from mcap.reader import make_reader
from mcap.writer import Writer

from aeroexec.catalog.loader import load_catalog
from aeroexec.catalog.model import Catalog
from aeroexec.catalog.paths import DEFAULT_CATALOG
from aeroexec.executive.behavior import GenericBehavior
from aeroexec.executive.bus import BusObserver
from aeroexec.executive.executive import Executive
from aeroexec.mission import APPENDIX_C, SessionConfig, simulate
from aeroexec.recording import Recorder
from aeroexec.recording.schemas import schema_for
from aeroexec.vehicles.null import NullVehicle

MISSION_TARGET = 1.3
MCAP_TARGET = 3.0


def _best(action: Callable[[], object], repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        action()
        best = min(best, time.perf_counter() - start)
    return best


# -- (a) the mission ---------------------------------------------------------------------------
def _quiet_simulate(config: SessionConfig, observers: list[BusObserver] | None = None) -> None:
    with contextlib.redirect_stdout(io.StringIO()):  # the mission script prints
        simulate(config, observers=observers or [])


def mission_overhead(workdir: Path, repeat: int) -> tuple[float, float, float, int]:
    """(unrecorded, recorded, mcap alone writing the recorded messages, messages)."""
    out = workdir / "mission.mcap"
    plain = SessionConfig(mission=APPENDIX_C)
    recorded = SessionConfig(mission=APPENDIX_C, record=out)
    _quiet_simulate(plain)  # also the warm-up: imports, caches
    _quiet_simulate(recorded)
    items = recorded_items(out)
    alone = workdir / "mission-alone.mcap"
    unrec = rec = mcap = float("inf")
    for _ in range(repeat):
        unrec = min(unrec, _best(lambda: _quiet_simulate(plain), 1))
        rec = min(rec, _best(lambda: _quiet_simulate(recorded), 1))
        mcap = min(mcap, _best(lambda: mcap_alone(alone, items), 1))
    return unrec, rec, mcap, len(items)


# -- (b) activations ---------------------------------------------------------------------------
def drive(catalog: Catalog, activations: int, observers: list[BusObserver]) -> None:
    executive = Executive(
        catalog, vehicle=NullVehicle(), library={}, stand_in=GenericBehavior, observers=observers
    )
    for i in range(activations // 2):
        executive.activate_behavior("GO_TO_POINT", {"coordinates": [i % 50, 1.0, 2.0]})
        executive.step()
        executive.activate_behavior("LAND")
        executive.step()


Item = tuple[str, str, int, Any]


def recorded_items(path: Path) -> list[Item]:
    """What the recorder wrote, read back: (schema, topic, log time, payload) in order, so
    the mcap-alone figure writes exactly the recorder's messages (derived ones included)."""
    items: list[Item] = []
    with open(path, "rb") as stream:
        for schema, channel, message in make_reader(stream).iter_messages(log_time_order=False):
            topic = channel.topic.removeprefix("/drone1/")
            name = schema.name if schema is not None else ""
            items.append((name, topic, message.log_time, json.loads(message.data)))
    return items


def mcap_alone(path: Path, items: list[Item]) -> None:
    """The same messages with the mcap library only (its default chunking and zstd)."""
    with open(path, "wb") as stream:
        writer = Writer(stream)
        writer.start(profile="aeroexec", library="benchmark")
        schemas: dict[str, int] = {}
        channels: dict[str, int] = {}
        for schema_name, topic, t, payload in items:
            channel = channels.get(topic)
            if channel is None:
                schema = schemas.get(schema_name)
                if schema is None:
                    definition = schema_for(schema_name)
                    schema = writer.register_schema(schema_name, "jsonschema", definition.data)
                    schemas[schema_name] = schema
                channel = writer.register_channel("/drone1/" + topic, "json", schema)
                channels[topic] = channel
            data = json.dumps(payload, separators=(",", ":")).encode()
            writer.add_message(channel, t, data, t)
        writer.finish()


def activation_costs(
    workdir: Path, activations: int, repeat: int
) -> tuple[float, float, float, int]:
    catalog = load_catalog(DEFAULT_CATALOG)
    out = workdir / "activations.mcap"
    alone = workdir / "alone.mcap"

    def recorded() -> None:
        with Recorder(out) as recorder:
            drive(catalog, activations, [recorder])

    recorded()
    items = recorded_items(out)

    off = rec = mcap = float("inf")
    for _ in range(repeat):
        off = min(off, _best(lambda: drive(catalog, activations, []), 1))
        rec = min(rec, _best(recorded, 1))
        mcap = min(mcap, _best(lambda: mcap_alone(alone, items), 1))
    return off, rec, mcap, len(items)


def _verdict(ratio: float, target: float) -> str:
    return "ok" if ratio <= target else "MISSED"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--activations", type=int, default=6_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args(argv)
    failed = False
    with tempfile.TemporaryDirectory() as tmp:
        workdir = Path(tmp)
        unrec, rec, mcap, messages = mission_overhead(workdir, args.repeat * 4)
        ratio = rec / unrec
        failed |= ratio > MISSION_TARGET
        print("(a) Appendix C mission, simulated (18.6 s of clock time)")
        print(f"    unrecorded:  {unrec * 1000:8.1f} ms")
        print(f"    recorded:    {rec * 1000:8.1f} ms  ({messages} messages)")
        print(
            f"    overhead: {ratio:.2f}x (target <= {MISSION_TARGET:g}x: "
            f"{_verdict(ratio, MISSION_TARGET)})"
        )
        print(
            f"    for scale: mcap alone writes these {messages} messages in {mcap * 1000:.1f} ms, "
            f"so no mcap-based recorder can go below {(unrec + mcap) / unrec:.2f}x here"
        )

        n = args.activations
        off, rec, mcap, count = activation_costs(workdir, n, args.repeat)
        ratio = rec / mcap
        failed |= ratio > MCAP_TARGET
        print(f"(b) {n} activations (GO_TO_POINT/LAND, NullVehicle), {count} messages")
        print(f"    recording off:        {n / off:10,.0f} activations/s (one step each)")
        print(
            f"    recording on:         {n / rec:10,.0f} activations/s "
            f"({rec / count * 1e6:.2f} us/message, whole path)"
        )
        print(
            f"    mcap alone (same msgs): {count / mcap:8,.0f} messages/s "
            f"= {n / mcap:,.0f} activations/s"
        )
        print(
            f"    recorded cost / mcap-alone cost: {ratio:.2f}x (target <= {MCAP_TARGET:g}x: "
            f"{_verdict(ratio, MCAP_TARGET)})"
        )
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
