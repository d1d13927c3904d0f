"""Mission fuzzing (issue 27): generated missions are legal for their catalog, a violation
is shrunk to a short mission that fails the same way under `aeroexec run` and `aeroexec
check`, the same seed gives the same bytes, the failure database runs first, `-m` mutates
a mission, and bad inputs are one line with exit 2."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import ClassVar

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from aeroexec.catalog.arguments import check_arguments
from aeroexec.catalog.loader import load_catalog
from aeroexec.catalog.paths import DEFAULT_CATALOG
from aeroexec.fuzz.oracle import Bench, Target, reference_problem, run_mission
from aeroexec.fuzz.search import Budget, Finding, fuzz, trimmed
from aeroexec.fuzz.steps import (
    ACTIVATE,
    EXECUTE,
    INHIBIT,
    Command,
    Fault,
    commands,
    ending_for,
    mission_text,
    world_text,
)
from aeroexec.fuzz.strategies import missions, vocabulary
from aeroexec.mission.session import SessionConfig, simulate
from aeroexec.vehicles import world

ROOT = Path(__file__).resolve().parent.parent
REAL = ROOT / "tests" / "fixtures" / "catalogs" / "real"
APPENDIX_C = ROOT / "missions" / "appendix_c.py"
#: A real catalog whose every behavior the standard library implements is rare: the
#: 2.0 default catalog runs with stand-ins for the rest.
AEROSTACK_20 = REAL / "Ahrovan+quadrotor_stack_configs__drone1_behavior_catalog__451fc45.yaml"


def aeroexec(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "aeroexec", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        check=False,
    )


# -- generation --------------------------------------------------------------------------
@pytest.mark.parametrize("path", [DEFAULT_CATALOG, AEROSTACK_20], ids=["default", "aerostack-2.0"])
@settings(
    max_examples=150,
    deadline=None,
    suppress_health_check=list(HealthCheck),
    derandomize=True,
    database=None,
)
@given(data=st.data())
def test_generated_commands_are_legal_for_the_catalog(path: Path, data: st.DataObject) -> None:
    catalog = load_catalog(path)
    words = vocabulary(catalog)
    mission = data.draw(missions(catalog, words))
    assert len(mission) <= 12
    for step in mission:
        if isinstance(step, Fault):
            assert step.kind in world.FAILURE_KINDS and 0 <= step.at_ds <= 600
            continue
        descriptor = catalog.behaviors[step.behavior]
        assert step.action in (EXECUTE, ACTIVATE, INHIBIT)
        if step.action == EXECUTE:
            assert not descriptor.recurrent, step
        checked = check_arguments(descriptor, dict(step.arguments))
        assert checked.ok, (step, checked.errors)


def test_boundaries_are_drawn() -> None:
    """Both ends of a range come up (the catalog's edges are where timeouts break)."""
    catalog = load_catalog(DEFAULT_CATALOG)
    seen: set[float] = set()

    # Derandomized: the same draws on every run, so the test cannot fail by chance.
    @settings(
        max_examples=300,
        deadline=None,
        suppress_health_check=list(HealthCheck),
        derandomize=True,
        database=None,
    )
    @given(missions(catalog, vocabulary(catalog, ())))
    def collect(mission: tuple) -> None:
        for step in commands(mission):
            for name, value in step.arguments:
                if step.behavior == "ROTATE" and name == "ANGLE":
                    seen.add(value)

    collect()
    assert {-360, 360} <= seen


def test_fault_kinds_are_the_simulators_registry(monkeypatch: pytest.MonkeyPatch) -> None:
    catalog = load_catalog(DEFAULT_CATALOG)
    assert vocabulary(catalog).fault_kinds == tuple(world.FAILURE_KINDS)
    monkeypatch.setattr(world, "FAILURE_KINDS", (*world.FAILURE_KINDS, "new_kind"))
    assert "new_kind" in vocabulary(catalog).fault_kinds


def test_a_mission_is_written_as_a_script_and_a_world_that_run() -> None:
    catalog = load_catalog(DEFAULT_CATALOG)
    mission = (
        Command(EXECUTE, "TAKE_OFF"),
        Command(ACTIVATE, "PAY_ATTENTION_TO_VISUAL_MARKERS"),
        Command(EXECUTE, "GO_TO_POINT", (("COORDINATES", [1, 2, 1]),)),
        Fault("low_battery", 35),
    )
    ending = ending_for(mission, catalog)
    assert ending.inhibit == ("PAY_ATTENTION_TO_VISUAL_MARKERS",) and ending.land == "LAND"
    text = mission_text(mission, ending)
    assert "api.execute_behavior('GO_TO_POINT', coordinates=[1, 2, 1])" in text
    assert text.rstrip().endswith("api.execute_behavior('LAND')")
    base = (ROOT / "aeroexec" / "data" / "worlds" / "default.yaml").read_text()
    assert "{kind: low_battery, at: 3.5}" in world_text(base, mission)
    bench = Bench.of(Target(str(DEFAULT_CATALOG)))
    judgement = run_mission(bench, mission)
    assert judgement.violations == ()
    assert judgement.result is not None and not judgement.result.final_state.flying
    assert [a.behavior for a in judgement.result.activations][-1] == "LAND"


# -- the executive's invariants -----------------------------------------------------------
def test_reference_problem_sees_books_that_do_not_add_up() -> None:
    class Spy:
        problems: ClassVar[list[str]] = []
        executive = None

        def session_started(self, executive) -> None:  # type: ignore[no-untyped-def]
            self.executive = executive

        def on_service_call(self, record) -> None:  # type: ignore[no-untyped-def]
            pass

        def on_topic(self, record) -> None:  # type: ignore[no-untyped-def]
            if record.topic == "vehicle/state" and self.executive is not None:
                self.problems.append(reference_problem(self.executive))
                manager = self.executive.resources
                if "VISUAL_MARKERS_RECOGNITION" in manager.references and len(self.problems) > 30:
                    manager.references["VISUAL_MARKERS_RECOGNITION"] += 1  # a broken count

    spy = Spy()
    simulate(SessionConfig(mission=APPENDIX_C), [spy])
    assert spy.problems[0] == ""
    broken = [p for p in spy.problems if p]
    assert broken and "VISUAL_MARKERS_RECOGNITION has reference count 2 but 1 holders" in broken[0]


# -- search and shrinking ------------------------------------------------------------------
def test_the_search_finds_and_shrinks_a_landing_that_times_out() -> None:
    """The bundled catalog's LAND has 15 s: from high up it times out in the air."""
    report = fuzz(Target(str(DEFAULT_CATALOG), fault_kinds=()), Budget(runs=100), seed_value=2)
    found = {f.name: f for f in report.findings}
    assert set(found) == {"ends_landed_disarmed"}
    mission = found["ends_landed_disarmed"].mission
    assert len(commands(mission)) <= 10
    assert mission[0] == Command(EXECUTE, "TAKE_OFF")
    assert any(c.behavior == "GO_TO_POINT" for c in commands(mission))


def test_each_finding_is_trimmed_to_the_steps_its_own_property_needs() -> None:
    """A mission shrunk under another property keeps steps this one does not need (a
    rotation, a second take-off, a fault): the deletion pass removes each of them, keeps
    what the violation needs, and the fuzzer applies it to every finding it reports."""
    target = Target(str(DEFAULT_CATALOG))
    bench = Bench.of(target)
    high = Command(EXECUTE, "GO_TO_POINT", (("COORDINATES", [0, 0, 100]),))
    padded = (
        Command(EXECUTE, "TAKE_OFF"),
        Command(EXECUTE, "ROTATE", (("ANGLE", 90),)),
        high,
        Command(EXECUTE, "TAKE_OFF"),
        Fault("low_battery", 600),
    )
    names = [v.name for v in run_mission(bench, padded).violations]
    assert names == ["ends_landed_disarmed"]
    finding = trimmed(bench, Finding("ends_landed_disarmed", "as found", padded))
    assert finding.mission == (Command(EXECUTE, "TAKE_OFF"), high)
    assert finding.message.startswith("the vehicle ends the session landed and disarmed")
    assert [v.name for v in run_mission(bench, finding.mission).violations] == names
    # what the property does not catch is not trimmed into it: a safe mission stays
    safe = (Command(EXECUTE, "TAKE_OFF"),)
    assert trimmed(bench, Finding("ends_landed_disarmed", "?", safe)).mission == safe
    # the fuzzer reports findings trimmed (here the database's, re-run first)
    report = fuzz(target, Budget(runs=1), seed_value=0, database=[padded])
    reported = {f.name: f.mission for f in report.findings}
    assert reported["ends_landed_disarmed"] == finding.mission


def test_the_same_seed_finds_the_same_and_another_seed_searches_elsewhere() -> None:
    target = Target(str(DEFAULT_CATALOG))
    first = fuzz(target, Budget(runs=120), seed_value=5)
    again = fuzz(target, Budget(runs=120), seed_value=5)
    assert first.findings == again.findings and first.runs == again.runs
    other = fuzz(target, Budget(runs=120), seed_value=6)
    assert other.runs != first.runs or other.findings != first.findings


def test_budget_parses_runs_and_times() -> None:
    assert Budget.parse("500") == Budget(runs=500)
    assert Budget.parse("90s") == Budget(seconds=90.0)
    assert Budget.parse("2m") == Budget(seconds=120.0)
    for bad in ("0", "-3", "ten", "0s", "5d"):
        with pytest.raises(ValueError):
            Budget.parse(bad)


# -- the command ---------------------------------------------------------------------------
@pytest.fixture(scope="module")
def fuzzed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("fuzz") / "out"
    done = aeroexec(
        "fuzz", str(DEFAULT_CATALOG), "--budget", "200", "--seed", "1", "--output-dir", str(out)
    )
    assert done.returncode == 1, done.stderr
    assert "2 properties violated" in done.stdout
    return out


def test_findings_are_written_and_fail_the_same_way_under_run_and_check(fuzzed: Path) -> None:
    findings = json.loads((fuzzed / "findings.json").read_text())
    names = [f["property"] for f in findings["findings"]]
    assert names == ["ends_landed_disarmed", "grounded_lands"]
    for entry in findings["findings"]:
        assert entry["reproduced"] is True and entry["commands"] <= 10
        folder = fuzzed / entry["folder"]
        assert {p.name for p in folder.iterdir()} == {
            "mission.py",
            "world.yaml",
            "run.mcap",
            "violation.txt",
        }
        record = folder / "again.mcap"
        ran = aeroexec(
            "run",
            str(folder / "mission.py"),
            "-c",
            str(DEFAULT_CATALOG),
            "-w",
            str(folder / "world.yaml"),
            "--spec",
            "aeroexec:safety",
            "-o",
            str(record),
        )
        assert ran.returncode == 1, ran.stderr
        assert f"error {entry['property']}" in ran.stdout
        checked = aeroexec("check", str(record), "--spec", "aeroexec:safety")
        assert checked.returncode == 1
        assert f"error {entry['property']}:" in checked.stdout
        # and the recording the fuzzer wrote is the one `run` writes
        assert (folder / "run.mcap").read_bytes() == record.read_bytes()
        record.unlink()


def test_the_same_seed_writes_the_same_bytes_and_jobs_do_not_matter(
    fuzzed: Path, tmp_path: Path
) -> None:
    again = tmp_path / "again"
    done = aeroexec(
        "fuzz", str(DEFAULT_CATALOG), "--budget", "200", "--seed", "1", "-j", "2",
        "--output-dir", str(again),
    )  # fmt: skip
    assert done.returncode == 1, done.stderr
    for name in ("findings.json", "failures.json"):
        assert (again / name).read_bytes() == (fuzzed / name).read_bytes()
    first = json.loads((fuzzed / "findings.json").read_text())["findings"][0]
    mission = (fuzzed / first["folder"] / "mission.py").read_text()
    # only the paths in its header's command lines differ
    assert mission.replace(str(fuzzed), "DIR") == (
        (again / first["folder"] / "mission.py").read_text().replace(str(again), "DIR")
    )


def test_the_database_runs_first_and_forgets_what_passes(tmp_path: Path) -> None:
    out = tmp_path / "out"
    base = ["fuzz", str(DEFAULT_CATALOG), "--faults", "none", "--output-dir", str(out)]
    done = aeroexec(*base, "--budget", "100", "--seed", "2")
    assert done.returncode == 1, done.stderr
    database = json.loads((out / "failures.json").read_text())
    assert [m["property"] for m in database["missions"]] == ["ends_landed_disarmed"]
    before = (out / "findings.json").read_bytes()
    again = aeroexec(*base, "--budget", "100", "--seed", "2")
    assert "1 from the database" in again.stdout
    assert (out / "findings.json").read_bytes() == before
    # a past failure that passes now (its mission lands from 1 m) is dropped
    database["missions"][0]["steps"] = [{"action": "execute", "behavior": "TAKE_OFF"}]
    database["missions"][0]["property"] = "ends_landed_disarmed"
    (out / "failures.json").write_text(json.dumps(database))
    third = aeroexec(*base, "--budget", "1", "--seed", "9")
    assert "1 past failures pass now" in third.stdout
    assert third.returncode == 0, third.stdout
    assert json.loads((out / "failures.json").read_text())["missions"] == []


def test_mutation_keeps_to_the_missions_own_commands(tmp_path: Path) -> None:
    out = tmp_path / "out"
    done = aeroexec(
        "fuzz", str(DEFAULT_CATALOG), "-m", str(APPENDIX_C), "--faults", "none",
        "--budget", "200", "--seed", "2", "--output-dir", str(out),
    )  # fmt: skip
    assert done.returncode == 1, done.stderr
    findings = json.loads((out / "findings.json").read_text())["findings"]
    flown = {"TAKE_OFF", "PAY_ATTENTION_TO_VISUAL_MARKERS", "GO_TO_POINT", "ROTATE", "LAND"}
    assert findings
    for entry in findings:
        assert {s["behavior"] for s in entry["steps"]} <= flown
        assert all("fault" not in s for s in entry["steps"])
        assert entry["reproduced"]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--budget", "ten"], "invalid value for --budget"),
        (["--faults", "meteor"], "unknown fault kind 'meteor'"),
        (["--spec", "missing.yaml"], "missing.yaml"),
    ],
)
def test_bad_inputs_are_one_line_and_exit_2(tmp_path: Path, args: list[str], message: str) -> None:
    done = aeroexec("fuzz", str(DEFAULT_CATALOG), "--output-dir", str(tmp_path / "o"), *args)
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], done.stderr


def test_a_damaged_database_is_named_with_its_place(tmp_path: Path) -> None:
    (tmp_path / "failures.json").write_text("{\n  oops\n")
    done = aeroexec("fuzz", str(DEFAULT_CATALOG), "--budget", "1", "--output-dir", str(tmp_path))
    assert done.returncode == 2
    assert done.stderr.startswith(f"{tmp_path / 'failures.json'}:2:3: error: not JSON")
