"""Properties (issue 25, docs/properties.md): offline cost, online cost, and agreement.

(a) Offline: 20 properties (the four of aeroexec:safety and 16 more over every kind of
    signal and operator, bounded windows up to 60 s included) on the recording of a
    one-hour patrol (benchmarks/replay.py's patrol-60: 65 laps of four waypoints and a
    40 s hover; about 36,000 ticks). The figure: extracting the signals and evaluating
    the 20 properties (`check_recording`). The baseline, the floor: reading the channels
    those properties need — the reader's pass over the file and a JSON decode of the
    messages on those channels, nothing else. Target: <= 2x.
(b) Online: the 10-minute patrol (patrol-10) simulated with `run --spec`'s monitor,
    against the same run without a monitor, both unrecorded (the strictest baseline: a
    recorded run costs more, and the line after the figures says what share of it the
    monitor is). Two figures: the 18 properties without an action (fed every message,
    judged at the end), and all 20, two with an action (a geofence and a battery floor,
    never violated: a vehicle signal against a number, judged on every vehicle state as
    it comes). Target: the monitor's extra CPU <= 10 % of the run, 1.1x.
(c) Identical: the monitor's verdicts against `check` on the recording of the same run
    (status, robustness, first violating interval of every property). Target: identical.
(d) Where a user feels it: the whole `aeroexec run --spec` process against `aeroexec run`
    (the 10-minute patrol, the 20 properties; CPU of each child process, bytecode cached
    as an installed tool has it). What a monitor costs there beyond (b) is starting it:
    importing numpy, which the unmonitored run never does (its own line: `import numpy`
    against an empty interpreter), the property modules, reading the property files.

Medians of --repeat interleaved rounds of CPU time (benchmarks/figures.py).

    .venv/bin/python benchmarks/properties.py [--repeat 5]
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import io
import os
import statistics
import sys
import tempfile
from pathlib import Path

import orjson
from figures import Figure, child_cpu, interleaved, timed
from replay import MISSION, PATROLS, long_endurance_world, record_patrol

from aeroexec.cli import BLAS_THREADS
from aeroexec.mission.session import SessionConfig, simulate
from aeroexec.properties.check import SERVICES, TOPICS, check_recording
from aeroexec.properties.monitor import PropertyMonitor
from aeroexec.properties.spec import PropertySet, load_properties, parse_properties
from aeroexec.recording import open_recording

FORMULAS = [
    ("ceiling", "always(altitude <= 120)", None),
    ("speed_limit", "always(speed <= 15)", None),
    ("battery_floor", "always(battery >= 0.05)", "land"),
    ("geofence", "always(distance_home <= 50)", "land"),
    (
        "low_battery_lands",
        "always((fault_low_battery >= 1) implies eventually[0:30](landed >= 1))",
        None,
    ),
    ("land_lands", "always((command_LAND >= 1) implies eventually[0:20](landed >= 1))", None),
    ("moves_flying", "always((active_GO_TO_POINT >= 1) implies (flying >= 1))", None),
    (
        "took_off_first",
        "always((active_GO_TO_POINT >= 1) implies once(active_TAKE_OFF >= 1))",
        None,
    ),
    ("lands_at_last", "eventually(active_LAND >= 1)", None),
    ("flying_armed", "always((flying >= 1) implies (armed >= 1))", None),
    (
        "go_to_ends",
        "always((command_GO_TO_POINT >= 1) implies eventually[0:60](active_GO_TO_POINT <= 0))",
        None,
    ),
    ("high_is_flying", "always(historically[0:5](altitude >= 1.4) implies (flying >= 1))", None),
    ("hover_still", "always((active_KEEP_HOVERING >= 1) implies (speed <= 0.5))", None),
    ("landed_low", "always((landed >= 1) implies (altitude <= 0.2))", None),
    ("no_go_to_landing", "always(not((active_GO_TO_POINT >= 1) and (active_LAND >= 1)))", None),
    ("disarmed_down", "always((armed <= 0) implies (flying <= 0))", None),
]


def spec_text() -> str:
    """The 16 properties besides aeroexec:safety, as a property file."""
    lines = ["properties:"]
    for name, formula, action in FORMULAS:
        lines += [f"  - name: {name}", f"    formula: '{formula}'", "    severity: warning"]
        if action:
            lines.append(f"    action: {action}")
    return "\n".join(lines) + "\n"


def twenty() -> PropertySet:
    own = parse_properties(spec_text(), "bench.yaml")
    safety = load_properties(["aeroexec:safety"]).properties
    return PropertySet((*safety, *own), ("aeroexec:safety", "bench.yaml"))


def whole_process(mission: Path, world: Path, directory: Path, repeat: int) -> list[Figure]:
    """(d): child processes, interleaved; bytecode written and read as an installed
    tool's is (this machine's PYTHONDONTWRITEBYTECODE would compile every module anew)."""
    spec = directory / "bench.yaml"
    spec.write_text(spec_text(), encoding="utf-8")
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
    run = [sys.executable, "-m", "aeroexec", "run", "-w", str(world), "-q"]
    plain = [*run, str(mission)]
    monitored = [*run, "--spec", "aeroexec:safety", "--spec", str(spec), str(mission)]
    # As `aeroexec` imports it: with one BLAS thread (aeroexec.cli.BLAS_THREADS).
    one_thread = f"import os; os.environ.setdefault{BLAS_THREADS!r}"
    numpy = [sys.executable, "-c", f"{one_thread}; import numpy"]
    empty = [sys.executable, "-c", one_thread]
    commands = {"plain": plain, "monitored": monitored, "numpy": numpy, "empty": empty}
    if importlib.util.find_spec("rtamt") is not None:  # the anchor, for scale
        commands["rtamt"] = [sys.executable, "-c", f"{one_thread}; import rtamt"]
    for command in commands.values():  # the bytecode caches
        child_cpu(command)
    samples: dict[str, list[float]] = {name: [] for name in commands}
    for _ in range(repeat):
        for name, command in commands.items():
            samples[name].append(child_cpu(command))
    cpu = {name: statistics.median(values) for name, values in samples.items()}
    if "rtamt" in cpu:
        floor = cpu["plain"] + cpu["rtamt"] - cpu["empty"]
        print(
            f"(for scale: RTAMT's import alone would make the run {floor * 1000:.1f} ms, "
            f"{floor / cpu['plain']:.2f}x: any STL library is imported before it monitors)"
        )
    return [
        Figure(
            "(d) whole process: aeroexec run --spec (20 properties), 10-min patrol",
            cpu["monitored"],
            cpu["plain"],
            "aeroexec run",
            1.1,
        ),
        Figure(
            "    floor: the unmonitored run plus importing numpy, which it never does",
            cpu["plain"] + cpu["numpy"] - cpu["empty"],
            cpu["plain"],
            "aeroexec run",
            1.1,
        ),
    ]


def read_channels(path: Path) -> None:
    """The floor: what any checker must do to get at the values."""
    for message in open_recording(path).messages():
        parts = message.channel.topic.split("/", 2)
        name = parts[2] if len(parts) == 3 else message.channel.topic
        if name in TOPICS or name in SERVICES:
            orjson.loads(message.data)


def run_patrol(
    mission: Path, world: Path, monitor: PropertyMonitor | None, record: Path | None = None
) -> None:
    with contextlib.redirect_stdout(io.StringIO()):
        simulate(
            SessionConfig(mission=mission, world=world, record=record),
            observers=[monitor] if monitor is not None else [],
        )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    props = twenty()
    assert len(props.properties) == 20
    figures = []
    with tempfile.TemporaryDirectory(prefix="aeroexec-properties-bench-") as tmp:
        directory = Path(tmp)
        world = long_endurance_world(directory)
        hour = record_patrol(directory, "patrol-60", world)
        offline = interleaved(
            {
                "read": timed(lambda: read_channels(hour)),
                "check": timed(lambda: check_recording(hour, props)),
            },
            args.repeat,
        )
        figures.append(
            Figure(
                "20 properties, 1-hour patrol (signals + evaluation)",
                offline["check"],
                offline["read"],
                "reading their channels",
                2.0,
            )
        )
        laps, hover = PATROLS["patrol-10"]
        mission = directory / "patrol-10.py"
        mission.write_text(MISSION.format(laps=laps, hover=hover), encoding="utf-8")
        passive = PropertySet(tuple(p for p in props.properties if not p.action), ())
        recorded = directory / "recorded.mcap"
        online = interleaved(
            {
                "plain": timed(lambda: run_patrol(mission, world, None)),
                "recorded": timed(lambda: run_patrol(mission, world, None, recorded)),
                "passive": timed(lambda: run_patrol(mission, world, PropertyMonitor(passive))),
                "acting": timed(lambda: run_patrol(mission, world, PropertyMonitor(props))),
            },
            args.repeat,
        )
        figures.append(
            Figure(
                "10-min patrol, 18 properties monitored (judged at the end)",
                online["passive"],
                online["plain"],
                "unmonitored, unrecorded",
                1.1,
            )
        )
        figures.append(
            Figure(
                "10-min patrol, 20 monitored, 2 with actions (judged on every state)",
                online["acting"],
                online["plain"],
                "unmonitored, unrecorded",
                1.1,
            )
        )
        extra = online["passive"] - online["plain"]
        print(
            f"(monitoring without actions adds {extra * 1000:.1f} ms; a recorded run, as "
            f"`aeroexec run -o` makes, takes {online['recorded'] * 1000:.1f} ms: "
            f"{extra / online['recorded'] * 100:.0f} % of it)"
        )
        monitor = PropertyMonitor(props)
        recording = directory / "monitored.mcap"
        with contextlib.redirect_stdout(io.StringIO()):
            simulate(SessionConfig(mission=mission, world=world, record=recording), [monitor])
        key = [(v.name, v.status, v.robustness, v.interval_s) for v in monitor.verdicts]
        again = check_recording(recording, props).verdicts
        same = key == [(v.name, v.status, v.robustness, v.interval_s) for v in again]
        figures += whole_process(mission, world, directory, args.repeat)
    ok = True
    for figure in figures:
        print(figure.line())
        ok &= figure.ok
    print(
        f"online vs offline verdicts of one flight: {'identical' if same else 'DIFFERENT'} "
        f"({len(key)} properties) | target identical {'ok' if same else 'MISSED'}"
    )
    ok &= same
    print("all targets met" if ok else "some targets MISSED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
