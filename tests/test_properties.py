"""Properties in signal temporal logic (issue 25): formulas, property files, signals from
real recordings of `aeroexec run`, the built-in set aeroexec:safety, `aeroexec check`."""

from __future__ import annotations

import contextlib
import io
import json
import math
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from aeroexec.catalog.paths import DEFAULT_CATALOG
from aeroexec.errors import Mark, PropertyError
from aeroexec.mission.session import SessionConfig, simulate
from aeroexec.properties.check import HELD, MISSING, VIOLATED, check_recording, evaluate
from aeroexec.properties.formula import compile_formula
from aeroexec.properties.signals import PERIOD_NS, SignalBuilder, is_known_signal
from aeroexec.properties.spec import load_properties, parse_properties

ROOT = Path(__file__).resolve().parent.parent
APPENDIX_C = ROOT / "missions" / "appendix_c.py"
FAULTS_WORLD = ROOT / "aeroexec" / "data" / "worlds" / "faults.yaml"
PATROL = """\
import executive_engine_api as api


def runMission():
    api.executeBehavior("TAKE_OFF")
    for lap in range(3):
        for point in ([3, 0, 1.5], [3, 3, 1.5], [0, 3, 1.5], [0, 0, 1.5]):
            api.executeBehavior("GO_TO_POINT", coordinates=point)
        api.executeBehavior("KEEP_HOVERING", duration=40)
    api.executeBehavior("LAND")
"""
NO_LANDING = """\
import executive_engine_api as api


def runMission():
    api.executeBehavior("TAKE_OFF")
    api.executeBehavior("GO_TO_POINT", coordinates=[0, 0, 2.0])
"""
LEFT_RUNNING = """\
import executive_engine_api as api


def runMission():
    api.executeBehavior("TAKE_OFF")
    api.activateBehavior("GO_TO_POINT", coordinates=[8, 8, 2.0])
"""


def record(tmp: Path, name: str, mission: str | Path, world: Path | None = None) -> Path:
    if isinstance(mission, str):
        path = tmp / f"{name}.py"
        path.write_text(mission, encoding="utf-8")
        mission = path
    out = tmp / f"{name}.mcap"
    with contextlib.redirect_stdout(io.StringIO()):
        simulate(SessionConfig(mission=mission, world=world, record=out))
    return out


@pytest.fixture(scope="module")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    tmp = tmp_path_factory.mktemp("props")
    return {
        "appendix_c": record(tmp, "appendix_c", APPENDIX_C),
        "patrol": record(tmp, "patrol", PATROL),
        "faults": record(tmp, "faults", APPENDIX_C, FAULTS_WORLD),
        "no_landing": record(tmp, "no_landing", NO_LANDING),
        "left_running": record(tmp, "left_running", LEFT_RUNNING),
    }


SAFETY = load_properties(["aeroexec:safety"])


def verdicts(path: Path, props=SAFETY) -> dict[str, object]:
    return {v.name: v for v in check_recording(path, props).verdicts}


# -- aeroexec:safety on real recordings -----------------------------------------------------
@pytest.mark.parametrize("name", ["appendix_c", "patrol"])
def test_safety_holds_on_the_thesis_mission_and_a_patrol(recordings, name) -> None:
    found = verdicts(recordings[name])
    assert {n: v.status for n, v in found.items()} == dict.fromkeys(found, HELD)
    assert set(found) == {
        "compatible_capabilities",
        "activations_answered",
        "ends_landed_disarmed",
        "grounded_lands",
    }


def test_safety_holds_on_a_one_hour_patrol(tmp_path) -> None:
    # The long patrol of benchmarks/properties.py: 65 laps of four waypoints and a 40 s
    # hover, on a battery that lasts (the default's lasts 20 minutes in the air).
    text = (ROOT / "aeroexec" / "data" / "worlds" / "default.yaml").read_text(encoding="utf-8")
    world = tmp_path / "endurance.yaml"
    world.write_text(
        text.replace("flight_endurance: 1200", "flight_endurance: 36000"), encoding="utf-8"
    )
    long_patrol = PATROL.replace("range(3)", "range(65)")
    report = check_recording(record(tmp_path, "hour", long_patrol, world), SAFETY)
    assert report.duration_s > 3500  # 35,676 ticks
    assert {v.name: v.status for v in report.verdicts} == dict.fromkeys(
        (
            "compatible_capabilities",
            "activations_answered",
            "ends_landed_disarmed",
            "grounded_lands",
        ),
        HELD,
    )


def test_a_seized_motor_that_never_lands_is_caught_when_the_motor_seizes(recordings) -> None:
    found = verdicts(recordings["faults"])
    grounded = found["grounded_lands"]
    assert grounded.status == VIOLATED
    # faults.yaml seizes the motor at 8.0 s; the session ends (vehicle lost) at 13.0 s.
    assert grounded.interval_s == (8.0, 13.0)
    assert found["ends_landed_disarmed"].status == VIOLATED
    assert found["ends_landed_disarmed"].interval_s[0] == pytest.approx(13.0)
    # Every activation was answered, even those whose start failed inside the call.
    assert found["activations_answered"].status == HELD


def _empty_battery_world(tmp: Path) -> Path:
    """The default world, its battery empty at 8.0 s: the vehicle is forced to land."""
    text = (ROOT / "aeroexec" / "data" / "worlds" / "default.yaml").read_text(encoding="utf-8")
    assert "failures: []" in text
    world = tmp / "empty_battery.yaml"
    world.write_text(
        text.replace("failures: []", "failures: [{kind: low_battery, at: 8.0, level: 0}]"),
        encoding="utf-8",
    )
    return world


def test_the_grounded_landing_bound_is_a_parameter_a_later_file_sets(tmp_path) -> None:
    flight = record(tmp_path, "empty", APPENDIX_C, _empty_battery_world(tmp_path))
    # Forced down from 1.3 m: grounded at 8.1 s, landed at 10.9 s, within the 30 s default.
    assert verdicts(flight)["grounded_lands"].status == HELD
    assert SAFETY.parameters[0].name == "land_within_s" and SAFETY.parameters[0].value == 30
    quick = tmp_path / "quick.yaml"
    quick.write_text("parameters:\n  land_within_s: 2.5\n", encoding="utf-8")
    tight = load_properties(["aeroexec:safety", str(quick)])
    grounded = verdicts(flight, tight)["grounded_lands"]
    assert grounded.status == VIOLATED
    # The ticks whose 2.5 s window ends before the landing at 10.9 s: 8.1 s to 8.3 s.
    assert grounded.interval_s == (8.1, 8.3)
    assert "landed within 2.5 s" in grounded.message()
    explained = aeroexec(
        "check", "--spec", "aeroexec:safety", "--spec", str(quick), "--explain", "grounded_lands"
    )
    assert f"land_within_s = 2.5 ({quick}:2)" in explained.stdout


@pytest.mark.parametrize(
    ("text", "where", "words"),
    [
        ("parameters:\n  land_within: 60\n", "p.yaml:2:3", "parameter 'land_within' is read by no"),
        ("parameters:\n  land_within_s: yes\n", "p.yaml:2:18", "must be a number"),
        ("parameters:\n  altitude: 3\n", "p.yaml:2:3", "is a signal"),
        ("parameters:\n  always: 3\n", "p.yaml:2:3", "a word of the formula language"),
        # A value that does not fit where a formula reads it: where it is set.
        ("parameters:\n  land_within_s: -1\n", "p.yaml:2:3", "= -1: a bound cannot be neg"),
        ("parameters:\n  land_within_s: 0.05\n", "p.yaml:2:3", "multiple of the sampling"),
    ],
)
def test_a_bad_parameter_is_one_error_at_its_place(tmp_path, text, where, words) -> None:
    spec = tmp_path / "p.yaml"
    spec.write_text(text, encoding="utf-8")
    with pytest.raises(PropertyError) as caught:
        load_properties_from(tmp_path, ["aeroexec:safety", "p.yaml"])
    assert str(caught.value.mark).startswith(where)
    assert words in caught.value.message


def load_properties_from(directory: Path, specs: list[str]):
    import os

    cwd = os.getcwd()
    os.chdir(directory)
    try:
        return load_properties(specs)
    finally:
        os.chdir(cwd)


def test_a_mission_that_never_lands_breaks_ends_landed_at_its_end(recordings) -> None:
    found = verdicts(recordings["no_landing"])
    assert found["ends_landed_disarmed"].status == VIOLATED
    report = check_recording(recordings["no_landing"], SAFETY)
    assert found["ends_landed_disarmed"].interval_s == (report.duration_s, report.duration_s)
    assert found["grounded_lands"].status == HELD


def test_an_activation_left_without_its_event_breaks_activations_answered(recordings) -> None:
    found = verdicts(recordings["left_running"])
    assert found["activations_answered"].status == VIOLATED


def _messages(builder: SignalBuilder, capabilities_at: dict[int, list[str]]) -> None:
    for tick, names in sorted(capabilities_at.items()):
        caps = [{"name": n, "references": 1} for n in names]
        builder.topic("list_of_active_capabilities", tick * PERIOD_NS, {"capabilities": caps})


def test_incompatible_capabilities_are_caught_at_the_tick_they_are_both_held() -> None:
    # The executive refuses such a state, so no mission reaches it: the stream is built
    # as the recorder would have written it, with the default catalog's conflicts.
    from aeroexec.catalog.loader import load_catalog

    catalog = load_catalog(DEFAULT_CATALOG)
    a, b = next(
        (name, other)
        for name in catalog.capabilities
        for other in sorted(catalog.conflicts_of(name))
    )
    builder = SignalBuilder(catalog.conflicts_of)
    _messages(builder, {0: [a], 25: [a, b], 31: [b], 40: []})
    [verdict] = [
        v for v in evaluate(SAFETY, builder.finish()) if v.name == "compatible_capabilities"
    ]
    assert verdict.status == VIOLATED
    assert verdict.interval_s == (2.5, 3.0)


def test_without_a_catalog_the_conflict_signal_is_missing_not_guessed() -> None:
    builder = SignalBuilder(None)
    _messages(builder, {0: ["A"], 5: ["A", "B"]})
    [verdict] = [
        v for v in evaluate(SAFETY, builder.finish()) if v.name == "compatible_capabilities"
    ]
    assert verdict.status == MISSING
    assert "catalog" in verdict.missing[0][1]


# -- formulas ----------------------------------------------------------------------------------
def compile_(text: str):
    return compile_formula(text, Mark("spec.yaml", 4, 14), is_known_signal)


def test_a_satisfied_boundary_is_told_from_a_violation() -> None:
    # fault at sample 10, landed at 40: within 5 s holds, within 2 s does not; the
    # robustness of both is 0 (0/1 signals on their boundary), so the verdict cannot
    # come from its sign.
    columns = {
        "fault_low_battery": [1.0 if k >= 10 else 0.0 for k in range(100)],
        "landed": [1.0 if k >= 40 else 0.0 for k in range(100)],
    }
    ok = compile_("always((fault_low_battery >= 1) implies eventually[0:5](landed >= 1))")
    bad = compile_("always((fault_low_battery >= 1) implies eventually[0:2](landed >= 1))")
    assert ok.evaluate(columns, 100).holds
    broken = bad.evaluate(columns, 100)
    assert not broken.holds
    assert broken.robustness == 0
    assert broken.interval == (10, 19)  # the first 10 samples whose window misses it


@pytest.mark.parametrize(
    ("text", "column", "words"),
    [
        ("always(alt <= 1)", 21, "unknown signal 'alt'"),
        ("from os import path", 14, "'from' has no place"),
        ("always(x) ; import os", 21, "unknown signal 'x'"),
        ("always(altitude <= 1", 34, "syntax error"),
        # The bound itself (RTAMT's own error had no place: the formula's start).
        ("always[0:0.05](altitude <= 1)", 23, "multiple of the sampling period"),
        ("always[0.5:0.2](altitude <= 1)", 21, "start is after its end"),
        ("always(altitude != 1)", 30, "'!=='"),
        ("always(altitude/2 <= 1)", 21, "unknown signal 'altitude/2'"),  # RTAMT's names
        ("always(altitude <= 1) always(speed <= 1)", 36, "expected the end of the formula"),
        ("always(altitude <= 0x10)", 33, "decimal"),
        ("always(altitude <= 1))", 35, "found ')'"),
        ("", 14, "empty formula"),
    ],
)
def test_a_bad_formula_is_one_error_at_its_column(text, column, words) -> None:
    with pytest.raises(PropertyError) as caught:
        compile_(text)
    assert caught.value.mark == Mark("spec.yaml", 4, column)
    assert words in caught.value.message


def test_a_formula_never_imports_what_it_names(tmp_path, monkeypatch) -> None:
    # RTAMT's language imports the module of a `from M import T` declaration.
    (tmp_path / "planted.py").write_text("raise SystemExit('imported')\n", encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(PropertyError):
        compile_("from planted import T\nalways(altitude <= 1)")
    assert "planted" not in sys.modules


def test_per_name_signals_are_zero_where_the_channel_exists() -> None:
    builder = SignalBuilder(None)
    builder.topic("list_of_active_behaviors", 0, {"behaviors": ["TAKE_OFF"]})
    builder.topic("list_of_active_behaviors", 3 * PERIOD_NS, {"behaviors": []})
    signals = builder.finish()
    assert signals.get("active_TAKE_OFF").tolist() == [1.0, 1.0, 1.0, 0.0]
    assert signals.get("active_LAND").tolist() == [0.0] * 4
    assert signals.get("altitude") is None
    assert "vehicle/state" in signals.why_missing("altitude")


@pytest.mark.parametrize("odd", [{"position": ["a", 0, 1]}, {"battery": "low"}, {"velocity": []}])
def test_states_none_of_which_is_numbers_leave_vehicle_signals_missing_and_say_why(odd) -> None:
    # A row with text in it is left out of the columns (a text battery, or no velocity,
    # makes no sample at all); when every state is so, the vehicle signals are missing,
    # with that reason: not a traceback, not "no vehicle/state messages".
    from aeroexec.properties.check import MISSING, evaluate
    from aeroexec.properties.spec import parse_properties

    builder = SignalBuilder(None)
    state = {"position": [0, 0, 1], "velocity": [0, 0, 0], "battery": 0.5, "flying": True}
    for k in range(3):
        builder.topic("vehicle/state", k * PERIOD_NS, {**state, **odd})
    signals = builder.finish()
    assert signals.length == 3
    assert signals.get("altitude") is None and signals.get("distance_home") is None
    assert signals.why_missing("altitude") == (
        "none of the recording's vehicle states is a row of numbers"
    )
    props = parse_properties("properties:\n  - {name: c, formula: 'always(altitude <= 9)'}\n", "p")
    (verdict,) = evaluate(props, signals)
    assert verdict.status == MISSING
    assert verdict.missing == (("altitude", signals.why_missing("altitude")),)


# -- property files ----------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("text", "where", "words"),
    [
        ("properties:\n  - name: a\n", "f.yaml:2:5", "needs 'formula'"),
        ("properties:\n  - {name: a, formula: 'always(x>1)'}\n", "f.yaml:2:32", "'x'"),
        (
            "properties:\n  - name: a\n    formula: always(altitude > 1)\n    action: jump\n",
            "f.yaml:4:13",
            "action 'jump'",
        ),
        ("props: []\n", "f.yaml:1:1", "unknown key 'props'"),
        ("properties: [\n", "f.yaml:2:1", "invalid YAML"),
        (
            "properties:\n  - name: a\n    formula: always(altitude > 1)\n"
            "  - name: a\n    formula: always(altitude > 2)\n",
            "f.yaml:4:11",
            "already defined",
        ),
    ],
)
def test_a_bad_property_file_is_one_error_with_its_place(text, where, words) -> None:
    with pytest.raises(PropertyError) as caught:
        if "already" in words:
            load_properties_text(text)
        else:
            parse_properties(text, "f.yaml")
    assert str(caught.value.mark) == where
    assert words in caught.value.message


def load_properties_text(text: str) -> None:
    # Duplicates are found across the set, as `--spec` loads it.
    import os
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "f.yaml")
        Path(path).write_text(text, encoding="utf-8")
        cwd = os.getcwd()
        os.chdir(tmp)
        try:
            load_properties(["f.yaml"])
        finally:
            os.chdir(cwd)


# -- the command line --------------------------------------------------------------------------
def aeroexec(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "aeroexec", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        check=False,
    )


SPEC = """\
properties:
  - name: ceiling
    description: never above 1.4 m
    formula: always(altitude <= 1.4)
  - name: legal_ceiling
    formula: always(altitude <= 120)
"""


def test_check_prints_each_violation_with_its_time_and_definition(recordings, tmp_path) -> None:
    spec = tmp_path / "spec.yaml"
    spec.write_text(SPEC, encoding="utf-8")
    rec = recordings["appendix_c"]
    done = aeroexec("check", str(rec), "--spec", str(spec))
    assert done.returncode == 1, done.stderr
    first = done.stdout.splitlines()[0]
    # Appendix C climbs to 1.45 m at 4.0 s (GO_TO_POINT relative [0, 0, 0.5]).
    assert first.startswith(f"{rec}: t=4.00s: error ceiling: never above 1.4 m: violated")
    assert first.endswith(f"({spec}:2)")
    assert "legal_ceiling" not in done.stdout
    held = aeroexec("check", str(rec))
    assert held.returncode == 0, held.stdout + held.stderr


def test_check_formats_carry_robustness_and_the_interval(recordings, tmp_path) -> None:
    spec = tmp_path / "spec.yaml"
    spec.write_text(SPEC, encoding="utf-8")
    rec = str(recordings["appendix_c"])
    data = json.loads(aeroexec("check", rec, "--spec", str(spec), "-f", "json").stdout)
    ceiling, legal = data["recordings"][0]["verdicts"]
    assert ceiling["status"] == "violated"
    assert ceiling["interval"]["start_s"] == 4.0
    assert -0.1 < ceiling["robustness"] < 0
    assert legal["status"] == "held" and legal["robustness"] > 118
    sarif = json.loads(aeroexec("check", rec, "--spec", str(spec), "-f", "sarif").stdout)
    [result] = sarif["runs"][0]["results"]
    assert result["ruleId"] == "ceiling"
    assert result["locations"][0]["physicalLocation"]["region"]["startLine"] == 2
    junit = ET.fromstring(aeroexec("check", rec, "--spec", str(spec), "-f", "junit").stdout)
    cases = {c.get("name"): c for c in junit.iter("testcase")}
    assert cases["ceiling"].find("failure") is not None
    assert cases["legal_ceiling"].find("failure") is None
    github = aeroexec("check", rec, "--spec", str(spec), "-f", "github").stdout
    assert github.startswith(f"::error file={spec},line=2,title=ceiling::")


def test_check_explains_a_property_and_refuses_a_bad_spec_in_one_line(tmp_path) -> None:
    spec = tmp_path / "spec.yaml"
    spec.write_text(SPEC, encoding="utf-8")
    explained = aeroexec("check", "--spec", str(spec), "--explain", "ceiling")
    assert explained.returncode == 0
    assert "altitude: height of the vehicle, up [m]" in explained.stdout
    bad = tmp_path / "bad.yaml"
    bad.write_text("properties:\n  - {name: a, formula: 'always(alt < 1)'}\n", encoding="utf-8")
    refused = aeroexec("check", "x.mcap", "--spec", str(bad))
    assert refused.returncode == 2
    assert refused.stderr == (
        f"{bad}:2:32: error: unknown signal 'alt' (the signals are listed in docs/properties.md)\n"
    )


def test_replay_check_passes_only_if_the_properties_hold(recordings, tmp_path) -> None:
    spec = tmp_path / "spec.yaml"
    spec.write_text(SPEC, encoding="utf-8")
    rec = str(recordings["appendix_c"])
    held = aeroexec("replay", rec, "--check", "--spec", "aeroexec:safety")
    assert held.returncode == 0, held.stdout + held.stderr
    assert "4 check(s): all properties hold" in held.stdout
    broken = aeroexec("replay", rec, "--check", "--spec", str(spec))
    assert broken.returncode == 1
    assert f"{rec} (replay): t=4.00s: error ceiling:" in broken.stdout
    assert "no differences" in broken.stdout  # the replay itself is equal: the property fails
    assert "replay written to" not in broken.stdout  # the scratch copy is not announced
    junit = ET.fromstring(aeroexec("replay", rec, "--spec", str(spec), "-f", "junit").stdout)
    assert junit.tag == "testsuites"
    [failure] = list(junit.iter("failure"))
    assert "ceiling" in failure.get("message", "") or failure.text
    without_check = aeroexec("replay", rec, "--spec", str(spec))
    assert without_check.returncode == 0  # reported, but --check decides the exit code
    kept = tmp_path / "again.mcap"
    written = aeroexec("replay", rec, "--spec", str(spec), "-o", str(kept))
    assert f"{kept}: t=4.00s: error ceiling" in written.stdout


def test_replay_spec_in_worker_processes_and_shards_gives_the_same_verdicts(
    recordings, tmp_path
) -> None:
    # Each replay is checked where it runs (a worker process, a Ray node) and its verdicts
    # travel with its result: --jobs 2 says what --jobs 1 says, and a shard's JSON report
    # carries its own replays' verdicts, which `report merge` puts back together.
    spec = tmp_path / "spec.yaml"
    spec.write_text(SPEC, encoding="utf-8")
    recs = [str(recordings["appendix_c"]), str(recordings["patrol"])]
    args = ["replay", *recs, "--spec", "aeroexec:safety", "--spec", str(spec), "--check"]
    alone = aeroexec(*args, "--jobs", "1")
    assert alone.returncode == 1  # appendix_c's replay climbs above 1.4 m
    assert f"{recs[0]} (replay): t=4.00s: error ceiling:" in alone.stdout
    assert f"{recs[1]} (replay): t=" in alone.stdout  # the patrol flies at 1.5 m too
    assert "2 recording(s), 12 check(s): 2 violated" in alone.stdout
    pooled = aeroexec(*args, "--jobs", "2")
    assert (pooled.returncode, pooled.stdout) == (alone.returncode, alone.stdout)
    whole = aeroexec(*args, "-f", "json")
    shards = []
    for k in (1, 2):
        done = aeroexec(*args, "--shard", f"{k}/2", "-f", "json")
        shard = json.loads(done.stdout)
        # A shard reports its own replays' verdicts, and fails --check on its own.
        names = [r["recording"] for r in shard["properties"]["recordings"]]
        assert names == [f"{r['recording']} (replay)" for r in shard["recordings"]]
        assert done.returncode == (1 if names else 0), done.stderr
        shards.append(tmp_path / f"shard-{k}.json")
        shards[-1].write_text(done.stdout, encoding="utf-8")
    merged = aeroexec("report", "merge", *map(str, shards), "--check", "-f", "json")
    assert (merged.returncode, json.loads(merged.stdout)) == (1, json.loads(whole.stdout))
    text = aeroexec("report", "merge", *map(str, shards), "--check")
    assert (text.returncode, text.stdout) == (alone.returncode, alone.stdout)
    junit = ET.fromstring(aeroexec("report", "merge", *map(str, shards), "-f", "junit").stdout)
    suites = [s.get("name") for s in junit.iter("testsuite")]
    assert f"properties: {recs[0]} (replay)" in suites
    # Shards of another property set are not one run.
    other = aeroexec("replay", *recs, "--spec", "aeroexec:safety", "--shard", "2/2", "-f", "json")
    shards[1].write_text(other.stdout, encoding="utf-8")
    refused = aeroexec("report", "merge", *map(str, shards))
    assert refused.returncode == 2 and "settings" in refused.stderr


def test_run_spec_reports_and_fails_on_a_violation(tmp_path) -> None:
    spec = tmp_path / "spec.yaml"
    spec.write_text(SPEC, encoding="utf-8")
    done = aeroexec("run", str(APPENDIX_C), "-q", "--spec", str(spec))
    assert done.returncode == 1
    assert f"{APPENDIX_C}: t=4.00s: error ceiling" in done.stdout
    assert "properties: 2 check(s): 1 violated" in done.stdout
    bad = tmp_path / "bad.yaml"
    bad.write_text("properties: 3\n", encoding="utf-8")
    refused = aeroexec(
        "run", str(APPENDIX_C), "-q", "--spec", str(bad), "-o", str(tmp_path / "x.mcap")
    )
    assert refused.returncode == 2
    assert refused.stderr.startswith(f"{bad}:1:13: error: 'properties' must be a list")
    assert not (tmp_path / "x.mcap").exists()  # refused before anything ran


def test_verify_checks_a_property_file_against_the_catalog(tmp_path) -> None:
    spec = tmp_path / "spec.yaml"
    spec.write_text(
        "properties:\n"
        "  - name: a\n"
        "    formula: always((active_GO_TO_PIONT >= 1) implies (flying >= 1))\n"
        "  - name: b\n"
        "    formula: always(capability_SELF_LOCALIZATION_BY_ODOMETRY >= 1)\n",
        encoding="utf-8",
    )
    done = aeroexec("verify", str(DEFAULT_CATALOG), "--spec", str(spec))
    assert done.returncode == 1
    assert (
        f"{spec}:3:22: error AX751 active_GO_TO_PIONT: no behavior GO_TO_PIONT in the catalog "
        "(did you mean 'GO_TO_POINT'?)"
    ) in done.stdout
    assert "AX752" not in done.stdout  # that capability exists
    bad = tmp_path / "bad.yaml"
    bad.write_text("properties:\n  - {name: a, formula: 'always(alt < 1)'}\n", encoding="utf-8")
    unread = aeroexec("verify", str(DEFAULT_CATALOG), "--spec", str(bad))
    assert unread.returncode == 2
    assert f"{bad}:2:32: error: unknown signal 'alt'" in unread.stderr


@pytest.mark.parametrize("velocity", [[None, 0.0, 0.0], [0.0, "1", 0.0], [0.0, 0.0], {}])
def test_a_state_whose_velocity_is_no_numbers_is_no_sample(velocity) -> None:
    # Its tick holds the state before (altitude included), as a malformed state's does;
    # position values that are no numbers are kept (NaN), as they always were.
    builder = SignalBuilder(None)
    state = {"position": [0.0, 0.0, 1.0], "velocity": [0.5, 0.0, 0.0], "battery": 1.0}
    state |= {"flying": True, "armed": True, "fault": ""}
    builder.topic("vehicle/state", 0, state)
    odd = {**state, "position": [0.0, 0.0, 2.0], "velocity": velocity}
    builder.topic("vehicle/state", PERIOD_NS, odd)
    builder.topic("vehicle/state", 2 * PERIOD_NS, {**state, "position": [0.0, None, 3.0]})
    signals = builder.finish()
    assert signals.get("altitude").tolist() == [1.0, 1.0, 3.0]
    assert signals.get("speed").tolist() == [0.5, 0.5, 0.5]
    assert math.isnan(signals.get("distance_home")[2])


def test_a_message_stamped_before_an_earlier_one_counts_from_that_ones_sample() -> None:
    # A live vehicle's stamps can go back a little. A late message counts from the
    # latest tick already seen (a tick over is what the online monitor judged), in the
    # whole signal and in a window (before, a binary search over unsorted stamps gave
    # whatever it found, or a crash).
    builder = SignalBuilder(None)
    state = {"position": [0.0, 0.0, 0.0], "velocity": [0.0, 0.0, 0.0], "battery": 1.0}
    state |= {"flying": True, "armed": True, "fault": ""}
    for tick, z, fault in [(1, 1.0, ""), (3, 2.0, "link_lost"), (2, 3.0, ""), (4, 4.0, "")]:
        position = [0.0, 0.0, z]
        builder.topic(
            "vehicle/state", tick * PERIOD_NS, {**state, "position": position, "fault": fault}
        )
    signals = builder.finish()
    assert signals.get("altitude").tolist() == [1.0, 1.0, 1.0, 3.0, 4.0]
    assert signals.get("link").tolist() == [1.0, 1.0, 1.0, 1.0, 1.0]
    window = builder.window(2, ["altitude", "link"])
    assert window is not None
    assert window["altitude"].tolist() == [1.0, 3.0, 4.0]
    assert window["link"].tolist() == [1.0, 1.0, 1.0]
    # A command keeps its own instant, in any order, and one past a window is not in it.
    for tick in (3, 1, 4):
        builder.topic("mission/command", tick * PERIOD_NS, {"behavior": "LAND"})
    commands = builder.window(1, ["command_LAND"], 3)
    assert commands is not None
    assert commands["command_LAND"].tolist() == [1.0, 0.0, 1.0]


def test_a_field_a_bag_import_only_defaulted_is_missing_not_guessed() -> None:
    builder = SignalBuilder(None)
    state = {
        "position": [0.0, 0.0, 1.0],
        "velocity": [0.0, 0.0, 0.0],
        "yaw": 0.0,
        "battery": 1.0,
        "flying": True,
        "armed": False,
        "fault": "",
        "defaulted": ["armed", "fault"],
    }
    for tick in range(3):
        builder.topic("vehicle/state", tick * PERIOD_NS, state)
    signals = builder.finish()
    assert signals.get("altitude").tolist() == [1.0, 1.0, 1.0]
    assert signals.get("armed") is None and signals.get("fault_stuck_motor") is None
    assert "import's default" in signals.why_missing("armed")
    [verdict] = [v for v in evaluate(SAFETY, signals) if v.name == "ends_landed_disarmed"]
    assert verdict.status == MISSING and verdict.missing[0][0] == "armed"
    assert builder.window(0, ["armed"]) is None


def test_an_imported_bag_is_checked_from_its_first_message(tmp_path) -> None:
    from aeroexec.bags.importer import import_bag

    out = tmp_path / "bag.mcap"
    import_bag(ROOT / "tests" / "fixtures" / "bags" / "aerostack_2017_first_view_ros1.bag", out)
    report = check_recording(out, SAFETY)
    assert 15.0 < report.duration_s < 17.0  # the bag's 16 s, not its epoch times
    found = {v.name: v for v in report.verdicts}
    # An Aerostack bag has no capability lists or activation calls: said, not guessed.
    assert found["compatible_capabilities"].status == MISSING
    assert found["activations_answered"].status == MISSING
    assert found["ends_landed_disarmed"].status == HELD
