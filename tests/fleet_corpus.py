"""A generated corpus of recordings with planted differences, for the fleet-scale replay
tests (test_fleet_*.py) and benchmarks/fleet.py.

Flight i takes off, flies 2 to 4 waypoints (seeded by i), hovers and lands, recorded
with the default catalog. Replayed against `narrowed` (GO_TO_POINT's COORDINATES in
[-2, 2] instead of [-100, 100]), a flight differs exactly when one of its waypoints is
outside [-2, 2]: the generator plants such a waypoint in every fifth flight and keeps
the others inside, so which recordings must differ is known from the plan, not from a
replay. Three more are planted broken: an empty file, a file that is not MCAP, and a
recording cut in half (incomplete: compared up to the cut, no difference).
"""

from __future__ import annotations

import contextlib
import io
import os
import random
from dataclasses import dataclass
from pathlib import Path

from test_replay_support import catalog_for

from aeroexec.mission.session import SessionConfig, simulate

MISSION = """\
import executive_engine_api as api


def runMission():
    api.executeBehavior("TAKE_OFF")
    for point in {points}:
        api.executeBehavior("GO_TO_POINT", coordinates=point)
    api.executeBehavior("KEEP_HOVERING", duration={hover})
    api.executeBehavior("LAND")
    return True
"""


@dataclass(frozen=True)
class Corpus:
    directory: Path
    #: Every file, sorted (what `aeroexec replay DIRECTORY` replays, in its order).
    files: tuple[str, ...]
    #: The catalog that makes the planted flights differ.
    narrowed: Path
    #: Names (as in the report) that must differ against `narrowed`.
    differing: frozenset[str]
    #: Names that must be error results (unreadable).
    broken: frozenset[str]
    #: Names that are cut short (compared up to the cut).
    incomplete: frozenset[str]


def _flight(index: int, planted: bool) -> str:
    rng = random.Random(index)
    points = [
        [round(rng.uniform(-1.8, 1.8), 1), round(rng.uniform(-1.8, 1.8), 1), 1.2]
        for _ in range(rng.randint(2, 4))
    ]
    if planted:  # one waypoint beyond the narrowed range, at a seeded leg
        points[rng.randrange(len(points))][rng.randrange(2)] = rng.choice([-1, 1]) * 2.5
    return MISSION.format(points=points, hover=rng.randint(1, 4))


def make_corpus(directory: Path, count: int, *, distinct: int | None = None) -> Corpus:
    """`count` recordings in `directory` (created). `distinct`: generate only that many
    flights and hard-link the others to them (a 10,000-recording corpus in seconds)."""
    directory.mkdir(parents=True, exist_ok=True)
    work = directory.parent / f".{directory.name}-missions"
    work.mkdir(exist_ok=True)
    narrowed = catalog_for(work, "narrowed")
    specials = {count // 3: "empty", count // 2: "garbage", (2 * count) // 3: "cut"}
    distinct = count if distinct is None else distinct
    differing: set[str] = set()
    broken: set[str] = set()
    incomplete: set[str] = set()
    files = []
    for index in range(count):
        path = directory / f"flight-{index:05}.mcap"
        name = str(path)
        files.append(name)
        special = specials.get(index)
        if special == "empty":
            path.write_bytes(b"")
            broken.add(name)
            continue
        if special == "garbage":
            path.write_text("this is not a recording\n")
            broken.add(name)
            continue
        source = index if special else index % distinct
        planted = source % 5 == 2 and special is None
        if source != index:
            os.link(directory / f"flight-{source:05}.mcap", path)
        else:
            mission = work / f"flight-{index:05}.py"
            mission.write_text(_flight(index, planted), encoding="utf-8")
            with contextlib.redirect_stdout(io.StringIO()):
                simulate(SessionConfig(mission=mission, record=path, seed=index))
        if special == "cut":
            data = path.read_bytes()
            path.unlink()  # (a hard link's other names keep the whole file)
            path.write_bytes(data[: len(data) // 2])
            incomplete.add(name)
        elif planted:
            differing.add(name)
    return Corpus(
        directory,
        tuple(sorted(files)),
        narrowed,
        frozenset(differing),
        frozenset(broken),
        frozenset(incomplete),
    )
