"""`aeroexec replay REC --inject FAULT@WHEN` (issue 26): WHEN read from the recording's
transitions, the fault struck in a closed-loop replay, the run recorded (with what was
injected), checked against aeroexec:safety, and reproduced byte for byte."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.errors import InjectionError
from aeroexec.mission.session import SessionConfig, simulate
from aeroexec.properties.spec import load_properties
from aeroexec.recording import open_recording
from aeroexec.recording.transitions import read_transitions, resolve_when
from aeroexec.replay.engine import ReplayOptions, replay_recording
from aeroexec.replay.inject import parse_injection
from aeroexec.replay.tasks import ReplayTask, run_task

ROOT = Path(__file__).resolve().parent.parent
MISSION = ROOT / "missions" / "appendix_c.py"
runner = CliRunner()


@pytest.fixture(scope="module")
def flight(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("inject") / "appendix_c.mcap"
    simulate(SessionConfig(mission=MISSION, record=path))
    return path


def test_transitions_are_the_activations_ends_and_capability_changes_in_order(
    flight: Path,
) -> None:
    transitions = read_transitions(flight)
    labels = [t.label for t in transitions]
    assert labels[:3] == [
        "capability:+SELF_LOCALIZATION_BY_ODOMETRY#1",
        "activate:TAKE_OFF#1",
        "end:TAKE_OFF#1",
    ]
    activations = [t.name for t in transitions if t.kind == "activate"]
    assert activations == [
        "TAKE_OFF",
        "PAY_ATTENTION_TO_VISUAL_MARKERS",
        "GO_TO_POINT",
        "GO_TO_POINT",
        "ROTATE",
        "GO_TO_POINT",
        "LAND",
    ]
    ends = {t.label: (t.time_ns, t.detail) for t in transitions if t.kind == "end"}
    assert ends["end:TAKE_OFF#1"] == (2_300_000_000, "GOAL_ACHIEVED")
    assert ends["end:PAY_ATTENTION_TO_VISUAL_MARKERS#1"][1] == "INTERRUPTED"
    times = [t.time_ns for t in transitions]
    assert times == sorted(times)


def test_when_strikes_after_the_transition_plus_its_offset(flight: Path) -> None:
    transitions = read_transitions(flight)
    end = 18_600_000_000
    assert resolve_when("end:TAKE_OFF", transitions, end, "r").due_ns == 2_300_000_001
    second = resolve_when("activate:GO_TO_POINT#2+0.5s", transitions, end, "r")
    assert second.transition is not None and second.transition.time_ns == 4_000_000_000
    assert second.due_ns == 4_500_000_001
    assert resolve_when("12.5s", transitions, end, "r").due_ns == 12_500_000_000
    released = resolve_when("capability:-PATH_PLANNING#1", transitions, end, "r")
    assert released.transition is not None and released.transition.name == "-PATH_PLANNING"


@pytest.mark.parametrize(
    ("when", "message"),
    [
        ("activate:GO_TO_PIONT", "has no activate:GO_TO_PIONT (it has TAKE_OFF,"),
        ("activate:GO_TO_POINT#4", "happens 3 times in the recording: #4 does not exist"),
        ("end:LAND#2", "end:LAND happens once in the recording"),
        ("30s", "past the end of the recording (it ends at 18.6 s)"),
        ("land:LAND", "expected a time (12.5s) or a transition"),
        ("capability:PATH_PLANNING", "referenced (+PATH_PLANNING) or released"),
        ("end:TAKE_OFF-5s", "is before the session began"),
    ],
)
def test_a_bad_when_is_one_line_naming_what_exists(flight: Path, when: str, message: str) -> None:
    with pytest.raises(InjectionError) as caught:
        resolve_when(when, read_transitions(flight), 18_600_000_000, str(flight))
    assert message in str(caught.value) and "\n" not in str(caught.value)
    result = runner.invoke(app, ["replay", str(flight), "--inject", f"lost_link@{when}"])
    assert result.exit_code == 2
    assert message in result.stderr and "Traceback" not in result.stderr


def test_a_bad_fault_is_refused_before_anything_runs(flight: Path) -> None:
    result = runner.invoke(app, ["replay", str(flight), "--inject", "engine_fire@1s"])
    assert result.exit_code == 2
    assert result.stderr.startswith("aeroexec replay: error: unknown fault kind 'engine_fire'")
    result = runner.invoke(app, ["replay", str(flight), "--inject", "lost_link"])
    assert result.exit_code == 2 and "expected FAULT@WHEN" in result.stderr


def test_an_injected_replay_is_recorded_checked_and_reproduces_byte_for_byte(
    flight: Path, tmp_path: Path
) -> None:
    out = tmp_path / "stuck.mcap"
    args = ["replay", str(flight), "--trust-recording", "--inject", "stuck_motor@activate:ROTATE"]
    result = runner.invoke(app, [*args, "--check", "-o", str(out)])
    # The seized motor leaves the vehicle in the air: aeroexec:safety is violated.
    assert result.exit_code == 1, result.output
    assert "injected: stuck_motor@activate:ROTATE (at 9.300 s)" in result.stdout
    assert "error grounded_lands" in result.stdout
    check = runner.invoke(app, ["check", str(out)])
    assert check.exit_code == 1 and "ends_landed_disarmed" in check.stdout
    metadata = open_recording(out).metadata["aeroexec"]
    assert json.loads(metadata["injected"]) == [
        {"fault": "stuck_motor", "when": "activate:ROTATE", "at_ns": 9_300_000_001}
    ]
    again = tmp_path / "again.mcap"
    assert runner.invoke(app, [*args, "-o", str(again)]).exit_code == 0
    assert again.read_bytes() == out.read_bytes()
    # Replaying the injected run strikes its recorded faults again: the same bytes.
    copy = tmp_path / "copy.mcap"
    shutil.copy(out, copy)
    third = tmp_path / "third.mcap"
    replay = runner.invoke(app, ["replay", str(copy), "--trust-recording", "-o", str(third)])
    assert replay.exit_code == 0 and "no differences" in replay.stdout
    assert third.read_bytes() == out.read_bytes()


def test_a_fault_the_mission_survives_passes_check_and_says_what_failed(
    flight: Path, tmp_path: Path
) -> None:
    options = ReplayOptions(
        trust_recording=True,
        injections=(parse_injection("lost_position@activate:GO_TO_POINT#1"),),
        output=str(tmp_path / "position.mcap"),
        properties=load_properties(["aeroexec:safety"]).documents,
    )
    result = run_task(ReplayTask(0, str(flight), str(flight), options))
    assert result.checked and result.violated == ()
    assert result.failures == (
        "#2 GO_TO_POINT relative_coordinates=[0, 0, 0.5]: PROCESS_FAILURE "
        "(vehicle fault: position_lost)",
    )
    # Appendix C's "Position unknown, landing..." path: it lands without the rest.
    assert result.diff is not None
    assert any("the mission took another path" in d.message for d in result.diff.differences)


def test_a_fault_due_after_the_session_never_strikes_and_says_so(flight: Path) -> None:
    options = ReplayOptions(
        trust_recording=True, injections=(parse_injection("lost_link@end:LAND"),)
    )
    result = replay_recording(flight, options)
    assert result.equal and result.failures == ()
    assert any("after the replay ended" in n and "never struck" in n for n in result.notes)


def test_open_loop_cannot_inject(flight: Path) -> None:
    result = runner.invoke(
        app, ["replay", str(flight), "--mode", "open", "--inject", "lost_link@1s"]
    )
    assert result.exit_code == 2 and "closed loop only" in result.stderr
