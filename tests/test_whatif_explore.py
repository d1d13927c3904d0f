"""`aeroexec explore` (issue 26): every fault kind at every transition of recorded missions.

On the default catalog and Appendix C every injection is held, failed cleanly or named
as a violation; a planted catalog ordering defect that replay and diff cannot see is
found; every counterexample reproduces (`aeroexec check` exits 1 on it, and its command
makes the same bytes again); the verdicts do not depend on the executor; a flight's
recording is explored in its simulated twin."""

from __future__ import annotations

import json
import shlex
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.mission.session import SessionConfig, simulate
from aeroexec.recording import open_recording
from aeroexec.replay.executors import ProcessExecutor
from aeroexec.vehicles.faults import KIND_NAMES
from aeroexec.whatif import ExploreOptions, ExploreResult, explore
from aeroexec.whatif.explore import FAILED, HELD, VIOLATED

ROOT = Path(__file__).resolve().parent.parent
MISSION = ROOT / "missions" / "appendix_c.py"
DEFECT = ROOT / "tests" / "fixtures" / "whatif" / "land_conflict.yaml"
runner = CliRunner()


def record(path: Path, catalog: Path | None = None) -> Path:
    config = SessionConfig(mission=MISSION, record=path)
    if catalog is not None:
        config = SessionConfig(mission=MISSION, record=path, catalog=catalog)
    assert simulate(config).outcome.returned
    return path


@pytest.fixture(scope="module")
def flights(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    where = tmp_path_factory.mktemp("explore")
    return {
        "default": record(where / "appendix_c.mcap"),
        "defect": record(where / "land_conflict.mcap", DEFECT),
    }


@pytest.fixture(scope="module")
def explored(
    flights: dict[str, Path], tmp_path_factory: pytest.TempPathFactory
) -> dict[str, ExploreResult]:
    out = tmp_path_factory.mktemp("found")
    return {
        name: explore([str(path)], ExploreOptions(out_dir=str(out / name), trust_recording=True))
        for name, path in flights.items()
    }


def cells(result: ExploreResult) -> dict[tuple[str, str], str]:
    return {(p.row, p.fault): result.outcome(p) for p in result.plan.probes}


def test_every_injection_is_held_failed_or_a_named_violation(
    explored: dict[str, ExploreResult],
) -> None:
    result = explored["default"]
    table = cells(result)
    labels = {row for row, _ in table}
    # Every transition of the mission is a row, every fault kind a column.
    assert {"activate:TAKE_OFF#1", "end:GO_TO_POINT#3", "activate:LAND#1"} <= labels
    assert {fault for _, fault in table} == set(KIND_NAMES)
    assert len(table) == len(labels) * len(KIND_NAMES)
    assert set(table.values()) <= {HELD, FAILED, VIOLATED} and not result.errors
    # Runs are shared by injections at the same instant, never simulated twice.
    assert len(result.results) < len(table)
    # A low battery and a gust are ridden out; a motor seized in flight never lands.
    assert {table[(row, "low_battery")] for row in labels} == {HELD}
    assert {table[(row, "wind_gust")] for row in labels} == {HELD}
    assert table[("activate:ROTATE#1", "stuck_motor")] == VIOLATED
    # After the landing the faults never strike: nothing is left to go wrong.
    assert {table[("end:LAND#1", kind)] for kind in KIND_NAMES} == {HELD}
    assert result.result(next(p for p in result.plan.probes if p.row == "end:LAND#1")).notes
    # A lost position estimate: Appendix C's "Position unknown, landing..." path, which
    # fails its goals but lands: failed cleanly, no property violated.
    assert table[("activate:GO_TO_POINT#1", "lost_position")] == FAILED
    # Each violation is named, by cause, with its recording and command kept.
    named = {(p.fault, p.row) for g in result.groups() for p in g.probes}
    violated = {(fault, row) for (row, fault), o in table.items() if o == VIOLATED}
    assert named == violated
    for run in result.results:
        if run.outcome == VIOLATED:
            assert run.kept is not None and Path(run.kept).is_file()
            assert run.reproduce is not None and run.reproduce.startswith("aeroexec replay ")
        else:
            assert run.kept is None
    causes = {(g.property, g.kind, g.behavior) for g in result.groups()}
    assert ("grounded_lands", "activate", "ROTATE") in causes


def test_a_planted_ordering_defect_is_found_by_explore_and_not_by_replay_or_diff(
    flights: dict[str, Path], explored: dict[str, ExploreResult], tmp_path: Path
) -> None:
    defect = flights["defect"]
    # Replay of the defective catalog's own recording: nothing differs, nothing violated.
    replay = runner.invoke(
        app,
        ["replay", str(defect), "--trust-recording", "--check", "--spec", "aeroexec:safety"],
    )
    assert replay.exit_code == 0, replay.output
    assert "no differences" in replay.stdout and "all properties hold" in replay.stdout
    # Nor does the same mission, same code, with the catalog changed to the defect
    # break a property; diff sees only LAND's new capability, a change, not a failure.
    moved = runner.invoke(
        app,
        [
            *("replay", str(flights["default"]), "-c", str(DEFECT), "--trust-recording"),
            *("--spec", "aeroexec:safety", "-o", str(tmp_path / "moved.mcap")),
        ],
    )
    assert moved.exit_code == 0 and "all properties hold" in moved.stdout
    diff = runner.invoke(app, ["diff", str(flights["default"]), str(defect)])
    assert "DOWNWARD_CAMERA" in diff.stdout and "ends" not in diff.stdout.split("\n", 1)[1]
    # Explore: with a lost position estimate the mission lands while marker recognition
    # still runs; LAND is refused and the vehicle is left in the air.
    found = explored["defect"]
    before = cells(explored["default"])
    after = cells(found)
    # (The rows both share: LAND's new capability is a row of the defect's only.)
    newly = {
        key
        for key, outcome in after.items()
        if outcome == VIOLATED and before.get(key, VIOLATED) != VIOLATED
    }
    assert ("activate:GO_TO_POINT#1", "lost_position") in newly
    assert {fault for _, fault in newly} == {"lost_position"}
    run = found.result(
        next(
            p
            for p in found.plan.probes
            if (p.row, p.fault) == ("activate:GO_TO_POINT#1", "lost_position")
        )
    )
    assert run.violated == ("ends_landed_disarmed",)
    assert any("LAND: refused" in f and "DOWNWARD_CAMERA" in f for f in run.failures)


def test_every_counterexample_reproduces(
    explored: dict[str, ExploreResult], tmp_path: Path
) -> None:
    """Each kept run: `aeroexec check` exits 1 on it, and its command makes it again,
    byte for byte, and exits 1 (benchmarks/explore.py repeats this 100 times)."""
    runs = [r for result in explored.values() for r in result.results if r.outcome == VIOLATED]
    assert len(runs) > 10
    for run in runs:
        assert run.kept is not None and run.reproduce is not None
        check = runner.invoke(app, ["check", run.kept])
        assert check.exit_code == 1, run.reproduce
        for name in run.violated:
            assert f"error {name}:" in check.stdout
    for run in runs[:: max(1, len(runs) // 6)]:  # a sample of every kind of cause
        assert run.kept is not None and run.reproduce is not None
        original = Path(run.kept).read_bytes()
        args = shlex.split(run.reproduce)
        assert args[:2] == ["aeroexec", "replay"]
        for attempt in range(3):
            again = tmp_path / f"again-{attempt}.mcap"
            args[-1] = str(again)
            result = runner.invoke(app, args[1:])
            assert result.exit_code == 1, result.output
            assert again.read_bytes() == original


def test_the_formats_say_the_same_thing(
    explored: dict[str, ExploreResult], flights: dict[str, Path], tmp_path: Path
) -> None:
    args = ["explore", str(flights["defect"]), "--trust-recording", "--faults"]
    args += ["lost_position,low_battery", "--output-dir", str(tmp_path / "out")]
    text = runner.invoke(app, args)
    assert text.exit_code == 1
    header = text.stdout.splitlines()[1].split()
    assert header == ["transition", "at", "s", "lost_position", "low_battery"]
    assert "ends_landed_disarmed at activate GO_TO_POINT" in text.stdout
    document = json.loads(runner.invoke(app, [*args, "-f", "json"]).stdout)
    assert document["violated"] is True and document["faults"] == ["lost_position", "low_battery"]
    violated = [i for i in document["injections"] if i["outcome"] == "violated"]
    assert violated and all(i["fault"] == "lost_position" for i in violated)
    assert sum(document["counts"].values()) == len(document["injections"])
    junit = ET.fromstring(runner.invoke(app, [*args, "-f", "junit"]).stdout)
    cases = junit.findall(".//testcase")
    assert len(cases) == len(document["injections"])
    assert len(junit.findall(".//failure")) == len(violated)
    github = runner.invoke(app, [*args, "-f", "github"]).stdout.splitlines()
    assert github and all(line.startswith("::error file=") for line in github)
    assert any("ends_landed_disarmed" in line for line in github)


def test_the_verdicts_do_not_depend_on_the_executor(
    flights: dict[str, Path], explored: dict[str, ExploreResult], tmp_path: Path
) -> None:
    options = ExploreOptions(out_dir=str(tmp_path), trust_recording=True)
    with ProcessExecutor(2) as pool:
        parallel = explore([str(flights["default"])], options, pool)
    assert cells(parallel) == cells(explored["default"])
    kept = {Path(r.kept).name: Path(r.kept).read_bytes() for r in parallel.results if r.kept}
    inline = {
        Path(r.kept).name: Path(r.kept).read_bytes() for r in explored["default"].results if r.kept
    }
    assert kept == inline


def test_bad_options_are_one_line_and_exit_2(flights: dict[str, Path], tmp_path: Path) -> None:
    base = ["explore", str(flights["default"]), "--output-dir", str(tmp_path)]
    for extra, message in (
        (["--faults", "fire"], "unknown fault kind 'fire'"),
        (["--offsets", "soon"], "'soon' is not a number of seconds"),
    ):
        result = runner.invoke(app, [*base, *extra])
        assert result.exit_code == 2
        assert result.stderr.startswith("aeroexec explore: error: ") and message in result.stderr
    missing = runner.invoke(app, ["explore", str(flights["default"])])
    assert missing.exit_code == 2 and "--output-dir" in missing.stderr


def test_offsets_strike_later_and_are_rows_of_their_own(
    flights: dict[str, Path], tmp_path: Path
) -> None:
    options = ExploreOptions(
        out_dir=str(tmp_path),
        kinds=("lost_link",),
        offsets=(0, 1_000_000_000),
        trust_recording=True,
    )
    result = explore([str(flights["default"])], options)
    rows = {p.row for p in result.plan.probes}
    assert {"end:TAKE_OFF#1", "end:TAKE_OFF#1+1s"} <= rows
    due = {p.row: result.results[p.run].run.due_ns for p in result.plan.probes}
    assert due["end:TAKE_OFF#1+1s"] - due["end:TAKE_OFF#1"] == 1_000_000_000


def test_a_flight_is_explored_in_its_simulated_twin(tmp_path: Path) -> None:
    sys.path.insert(0, str(ROOT / "tests"))
    from live_helpers import free_udp_port, mavsim_thread, write_mission

    mission = write_mission(
        tmp_path,
        "    api.executeBehavior('TAKE_OFF')\n"
        "    api.executeBehavior('GO_TO_POINT', coordinates=[2, 0, 1])\n"
        "    api.executeBehavior('LAND')\n",
    )
    port = free_udp_port()
    flight = tmp_path / "flight.mcap"
    with mavsim_thread(f"udpout:127.0.0.1:{port}"):
        flown = runner.invoke(
            app, ["fly", str(mission), "--connect", f"udpin:127.0.0.1:{port}", "-o", str(flight)]
        )
    assert flown.exit_code == 0, flown.output
    out = tmp_path / "out"
    result = explore(
        [str(flight)],
        ExploreOptions(out_dir=str(out), kinds=("stuck_motor", "wind_gust"), trust_recording=True),
    )
    (twin,) = result.flights
    assert result.flights[twin] == str(flight) and Path(twin).is_file()
    metadata = open_recording(twin).metadata["aeroexec"]
    assert metadata["clock"] == "sim" and metadata["mission"] == "mission.py"
    table = cells(result)
    assert table[("activate:GO_TO_POINT#1", "stuck_motor")] == VIOLATED
    assert table[("activate:GO_TO_POINT#1", "wind_gust")] == HELD
    # The counterexample's command replays the twin, which starts where the flight did.
    run = next(r for r in result.results if r.outcome == VIOLATED)
    assert run.reproduce is not None and f"aeroexec replay {twin} " in run.reproduce
    again = runner.invoke(app, shlex.split(run.reproduce)[1:])
    assert again.exit_code == 1, again.output
