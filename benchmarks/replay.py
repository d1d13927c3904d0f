"""Benchmark: replay speed (multiple of real time) and peak memory vs recording length.

Records patrol missions (take off; laps of four waypoints and a hover; land) in a world
whose battery lasts for hours:

* patrol-10: about 10 simulated minutes, 11 laps with 40 s hovers;
* patrol-60: about 60 minutes, 65 laps with 40 s hovers (a busy hour: 6x the commands);
* hover-60: about 60 minutes, 11 laps with 5.5 min hovers (the commands of patrol-10,
  6x its messages).

Each is replayed with its own catalog, closed loop and open loop, measuring

* speed: simulated seconds of the recording / wall-clock seconds of the replay (reading
  the original, replaying it, diffing the two: what `aeroexec replay --check` does);
* peak memory (tracemalloc, in separate runs so it does not slow the timed ones).

Targets (docs/design.md#performance-targets): replay >= 1000x real time; memory flat
in recording size: the peak for hover-60 <= 1.10x the peak for patrol-10 (same commands, 6x the
length). Replay keeps one small summary per mission command, by design; patrol-60 vs
hover-60 shows that cost per command (reported, no target). Prints every figure with
its target; exits 1 if a target is missed.

    .venv/bin/python benchmarks/replay.py [--repeat 2]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

from aeroexec.mission.session import SessionConfig, simulate
from aeroexec.recording import open_recording
from aeroexec.replay import Mode, ReplayOptions, replay_recording
from aeroexec.vehicles.world import DEFAULT_WORLD

SPEED_TARGET = 1000.0
MEMORY_RATIO_TARGET = 1.10
#: Simulated seconds the four 3 m legs of one lap take.
LEGS_SECONDS = 14.8
#: name -> (laps, hover seconds per lap)
PATROLS = {"patrol-10": (11, 40), "patrol-60": (65, 40), "hover-60": (11, 315)}

MISSION = """\
import executive_engine_api as api

LAPS = {laps}
HOVER = {hover}


def runMission():
    api.executeBehavior("TAKE_OFF")
    for lap in range(LAPS):
        for point in ([3, 0, 1.5], [3, 3, 1.5], [0, 3, 1.5], [0, 0, 1.5]):
            api.executeBehavior("GO_TO_POINT", coordinates=point)
        api.executeBehavior("KEEP_HOVERING", duration=HOVER)
    api.executeBehavior("LAND")
    return True
"""


def long_endurance_world(directory: Path) -> Path:
    """The default world with a battery that lasts ten hours in the air."""
    text = DEFAULT_WORLD.read_text(encoding="utf-8")
    for old, new in (
        ("flight_endurance: 1200", "flight_endurance: 36000"),
        ("idle_endurance: 7200", "idle_endurance: 72000"),
    ):
        if old not in text:
            raise SystemExit(f"default world changed: cannot find {old!r}")
        text = text.replace(old, new)
    path = directory / "endurance.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def record_patrol(directory: Path, name: str, world: Path) -> Path:
    laps, hover = PATROLS[name]
    mission = directory / f"{name}.py"
    mission.write_text(MISSION.format(laps=laps, hover=hover), encoding="utf-8")
    path = directory / f"{name}.mcap"
    with contextlib.redirect_stdout(io.StringIO()):
        simulate(SessionConfig(mission=mission, world=world, record=path))
    return path


def replay(path: Path, mode: Mode) -> float:
    """Wall-clock seconds of one replay (read + replay + diff); checks it is equal."""
    start = time.perf_counter()
    # The benchmark's own recordings: their scripts run (what replay measured before
    # closed loop stopped running recorded code by default).
    result = replay_recording(path, ReplayOptions(mode=mode, trust_recording=True))
    elapsed = time.perf_counter() - start
    if not result.equal:
        raise SystemExit(f"{path}: {mode.value} replay differs: {result.error or result.diff}")
    return elapsed


def peak_kib(path: Path, mode: Mode) -> float:
    tracemalloc.start()
    try:
        replay_recording(path, ReplayOptions(mode=mode, trust_recording=True))
        return tracemalloc.get_traced_memory()[1] / 1024
    finally:
        tracemalloc.stop()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=2, help="timed runs; the best counts")
    args = parser.parse_args()
    ok = True
    with tempfile.TemporaryDirectory(prefix="aeroexec-replay-bench-") as tmp:
        directory = Path(tmp)
        world = long_endurance_world(directory)
        recordings = {name: record_patrol(directory, name, world) for name in PATROLS}
        print("recordings:")
        durations: dict[str, float] = {}
        commands: dict[str, int] = {}
        for name, path in recordings.items():
            survey = open_recording(path).survey()
            first, last = survey.first_log_time_ns or 0, survey.last_log_time_ns or 0
            durations[name] = (last - first) / 1e9
            commands[name] = survey.topic_counts().get("/drone1/mission/command", 0)
            print(
                f"  {name:9}  {durations[name] / 60:5.1f} simulated min  "
                f"{commands[name]:>4} commands  {survey.message_count:>7} messages  "
                f"{path.stat().st_size / 1e6:5.1f} MB"
            )
        print(f"speed (simulated s / wall s; target >= {SPEED_TARGET:,.0f}x):")
        for mode in (Mode.closed, Mode.open):
            for name, path in recordings.items():
                wall = min(replay(path, mode) for _ in range(max(1, args.repeat)))
                speed = durations[name] / wall
                met = speed >= SPEED_TARGET
                ok &= met
                print(
                    f"  {mode.value:6} {name:9}  {wall:6.2f} s wall  {speed:7,.0f}x real time  "
                    f"{'ok' if met else 'MISSED'}"
                )
        print(
            "peak memory (tracemalloc; target: hover-60 <= "
            f"{MEMORY_RATIO_TARGET:.2f}x patrol-10, i.e. flat in recording size):"
        )
        for mode in (Mode.closed, Mode.open):
            peaks = {name: peak_kib(path, mode) for name, path in recordings.items()}
            ratio = peaks["hover-60"] / peaks["patrol-10"]
            met = ratio <= MEMORY_RATIO_TARGET
            ok &= met
            extra = commands["patrol-60"] - commands["hover-60"]
            per_command = (peaks["patrol-60"] - peaks["hover-60"]) / max(1, extra)
            print(
                f"  {mode.value:6}  patrol-10 {peaks['patrol-10']:7,.0f} KiB  "
                f"hover-60 {peaks['hover-60']:7,.0f} KiB  ratio {ratio:4.2f}  "
                f"{'ok' if met else 'MISSED'}"
            )
            print(
                f"          patrol-60 {peaks['patrol-60']:7,.0f} KiB: "
                f"{per_command * 1024:,.0f} bytes per extra mission command (both runs' summaries)"
            )
    print("all targets met" if ok else "some targets MISSED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
