"""Issue 12's acceptance: a behavior package in a temporary folder, configured only
through pyproject.toml, runs in `run`, `fly` (against `aeroexec mavsim`) and closed-loop
`replay`; replaying with a modified version reports exactly the changed outcomes plus
"code changed"; bad plugins are one line naming the file, exit 2. The path itself runs
the real `aeroexec` in subprocesses from the project folder; the listings and the other
commands' error lines run the same command line in-process.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from test_mavlink_flight import Proc, free_udp_port, procs, start_mavsim, stop_mavsim
from typer.testing import CliRunner

from aeroexec.catalog import DEFAULT_CATALOG
from aeroexec.cli import app
from aeroexec.recording import open_recording

__all__ = ["procs"]  # the fixture, used by name

CATALOG = DEFAULT_CATALOG.read_text(encoding="utf-8").replace(
    "behavior_lists:",
    """\
  - behavior: SURVEY
    timeout: 60
    recurrent: no
    incompatible_lists: [motion_behaviors]
    capabilities: [SETPOINT_BASED_FLIGHT_CONTROL]
    arguments:
      - argument: side
        allowed_values: [0.5, 10]

behavior_lists:""",
    1,
)

PACKAGE = {
    "dronebehaviors/__init__.py": """\
        from dronebehaviors.precise import PreciseGoToPoint
        from dronebehaviors.survey import Survey

        __all__ = ["PreciseGoToPoint", "Survey"]
        """,
    "dronebehaviors/survey.py": """\
        import math

        from aeroexec.executive import Behavior, Finished, Situation


        class Survey(Behavior):
            \"\"\"Fly out SIDE metres east and back, at the current altitude.\"\"\"

            name = "SURVEY"
            argument_names = ("SIDE",)
            reach = 0.2

            def check_situation(self, beliefs):
                return Situation.ok_if(beliefs.holds("flying(self)"), "not flying")

            def on_start(self, args):
                x, y, z = self.vehicle.state().position
                self.legs = [(x + float(args["SIDE"]), y, z), (x, y, z)]
                self.vehicle.go_to(*self.legs[0])

            def on_run(self):
                if math.dist(self.vehicle.state().position, self.legs[0]) <= self.reach:
                    self.legs.pop(0)
                    if not self.legs:
                        return Finished(detail="surveyed")
                    self.vehicle.go_to(*self.legs[0])
                return None
        """,
    "dronebehaviors/precise.py": """\
        from aeroexec.behaviors import GoToPoint


        class PreciseGoToPoint(GoToPoint):
            tolerance = 0.05
        """,
}

MISSION = """\
import executive_engine_api as api


def runMission():
    api.executeBehavior('TAKE_OFF')
    api.executeBehavior('SURVEY', side=2)
    api.executeBehavior('GO_TO_POINT', coordinates=[1, 1, 1])
    api.executeBehavior('KEEP_HOVERING', duration=1)
    api.executeBehavior('LAND')
"""


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def make_project(root: Path, tolerance: str = "0.05") -> Path:
    write(
        root / "pyproject.toml",
        '[tool.aeroexec]\nbehaviors = ["dronebehaviors"]\ncatalog = "catalog.yaml"\n',
    )
    write(root / "catalog.yaml", CATALOG)
    write(root / "mission.py", MISSION)
    for name, text in PACKAGE.items():
        write(root / name, text.replace("tolerance = 0.05", f"tolerance = {tolerance}"))
    return root


def aeroexec(cwd: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "aeroexec", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=120,
    )


def differences(report: str) -> list[str]:
    return [line for line in report.splitlines() if line.startswith("  #")]


def test_a_configured_package_runs_replays_and_its_change_is_reported(tmp_path: Path) -> None:
    project = make_project(tmp_path / "project")
    run = aeroexec(project, "run", "mission.py", "--output", "base.mcap")
    assert run.returncode == 0, run.stderr
    assert run.stderr == ""
    assert "] end      SURVEY GOAL_ACHIEVED" in run.stdout
    assert "5 activations: 5 GOAL_ACHIEVED, 0 rejected" in run.stdout
    code = open_recording(project / "base.mcap").metadata["behaviors"]
    assert code["SURVEY"].startswith("dronebehaviors.survey:Survey sha256:")
    assert code["GO_TO_POINT"].startswith("dronebehaviors.precise:PreciseGoToPoint sha256:")

    same = aeroexec(
        project, "replay", "base.mcap", "--mission", "mission.py", "--check", "-o", "again.mcap"
    )
    assert same.returncode == 0, same.stdout + same.stderr
    assert "no differences (5 commands compared)" in same.stdout
    assert "code changed" not in same.stdout
    assert (project / "again.mcap").read_bytes() == (project / "base.mcap").read_bytes()

    # The same project elsewhere with a tighter tolerance: the replay reports exactly
    # what a fresh run of it changes, and which code changed.
    tighter = make_project(tmp_path / "tighter", tolerance="0.005")
    fresh = aeroexec(tighter, "run", "mission.py", "--output", "fresh.mcap", "-q")
    assert fresh.returncode == 0, fresh.stderr
    expected = aeroexec(tighter, "diff", str(project / "base.mcap"), "fresh.mcap")
    replayed = aeroexec(
        tighter, "replay", str(project / "base.mcap"), "--mission", "mission.py", "--check"
    )
    assert replayed.returncode == 1, replayed.stdout + replayed.stderr
    changed = differences(replayed.stdout)
    assert changed and changed == differences(expected.stdout)
    assert any("GO_TO_POINT" in line for line in changed)
    assert not any("SURVEY" in line for line in changed)
    assert replayed.stdout.splitlines()[0].endswith("; code changed")
    was = code["GO_TO_POINT"].split("sha256:")[1]
    now = open_recording(tighter / "fresh.mcap").metadata["behaviors"]["GO_TO_POINT"]
    assert [line for line in replayed.stdout.splitlines() if "code changed:" in line] == [
        "  code changed: GO_TO_POINT: dronebehaviors.precise:PreciseGoToPoint source changed "
        f"(sha256:{was} -> {now.split('sha256:')[1]})"
    ]


def test_the_configured_package_flies_against_mavsim(tmp_path: Path, procs: list[Proc]) -> None:
    project = make_project(tmp_path / "project")
    port = free_udp_port()
    stats_path = tmp_path / "mavsim.json"
    mavsim = start_mavsim(procs, port, stats_path)
    flight = subprocess.run(
        [
            sys.executable,
            "-m",
            "aeroexec",
            "fly",
            "mission.py",
            "--connect",
            f"udpin:127.0.0.1:{port}",
            "--output",
            "live.mcap",
        ],
        cwd=project,
        capture_output=True,
        text=True,
        timeout=60,
    )
    stats = stop_mavsim(mavsim, stats_path)
    assert flight.returncode == 0, flight.stdout + flight.stderr
    assert "] end      SURVEY GOAL_ACHIEVED" in flight.stdout
    assert "5 activations: 5 GOAL_ACHIEVED, 0 rejected" in flight.stdout
    assert stats["final"]["mode"] == "LAND" and not stats["final"]["armed"]
    recording = open_recording(project / "live.mcap")
    assert recording.metadata["aeroexec"]["clock"] == "wall"
    assert recording.metadata["behaviors"]["SURVEY"].startswith("dronebehaviors.survey:Survey ")
    assert recording.attachment("behaviors/dronebehaviors.survey.py") is not None


@pytest.mark.parametrize(
    ("name", "text", "where", "problem"),
    [
        (
            "survey.py",
            "import math\nfrom dronebehaviors.geometry import square\n",
            "dronebehaviors/survey.py:2:1: error: importing behaviors entry 'dronebehaviors' "
            "failed: ModuleNotFoundError",
            "No module named 'dronebehaviors.geometry'",
        ),
        (
            "survey.py",
            "class Survey:\n    name = 'SURVEY'\n\n    def on_run(self):\n        return None\n",
            "dronebehaviors/survey.py:1:1: error: Survey has behavior hooks but is not a "
            "subclass of aeroexec.executive.Behavior",
            "",
        ),
        (
            "precise.py",
            "from aeroexec.behaviors import GoToPoint\n\n\nclass PreciseGoToPoint(GoToPoint):\n"
            "    name = 'SURVEY'\n",
            "dronebehaviors/survey.py:",
            "error: behavior SURVEY is implemented twice: dronebehaviors.survey:Survey",
        ),
        (
            "survey.py",
            "from aeroexec.executive import Behavior\n\nclass Survey(Behavior)\n    name = 'S'\n",
            "dronebehaviors/survey.py:3:",
            "error: invalid Python: expected ':'",
        ),
    ],
    ids=["import-error", "not-a-behavior", "duplicate-name", "syntax-error"],
)
def test_a_bad_plugin_is_one_line_naming_its_file_and_exit_2(
    tmp_path: Path, name: str, text: str, where: str, problem: str
) -> None:
    project = make_project(tmp_path / "project")
    write(project / "dronebehaviors" / name, text)
    done = aeroexec(project, "run", "mission.py")
    assert done.returncode == 2, (done.stdout, done.stderr)
    (line,) = done.stderr.splitlines()
    assert line.startswith(where) and problem in line, line
    assert done.stdout == ""


def test_every_command_that_loads_behaviors_reports_a_bad_one_alike(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    project = make_project(tmp_path / "project")
    write(project / "dronebehaviors" / "survey.py", "import math\nimport not_installed_xyz\n")
    monkeypatch.chdir(project)
    for command in (["behaviors"], ["verify"], ["replay", "none.mcap"], ["fly", "mission.py"]):
        result = CliRunner().invoke(app, command)
        assert result.exit_code == 2, (command, result.output)
        assert result.stderr.splitlines() == [
            "dronebehaviors/survey.py:2:1: error: importing behaviors entry 'dronebehaviors' "
            "failed: ModuleNotFoundError: No module named 'not_installed_xyz'"
        ]


def test_behaviors_lists_the_package_and_verify_checks_the_catalog_against_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    project = make_project(tmp_path / "project")
    monkeypatch.chdir(project)
    listed = CliRunner().invoke(app, ["behaviors", "--format", "json"])
    assert listed.exit_code == 0, listed.stderr
    document = json.loads(listed.stdout)
    by_name = {i["behavior"]: i for i in document["implementations"]}
    assert by_name["SURVEY"]["implementation"] == "dronebehaviors.survey:Survey"
    assert by_name["SURVEY"]["file"] == "dronebehaviors/survey.py"
    assert by_name["SURVEY"]["source"] == "pyproject.toml"
    assert by_name["GO_TO_POINT"]["overrides_standard"] is True
    assert by_name["LAND"]["source"] == "standard library"
    assert document["unimplemented"] == []
    # The catalog calls the argument POSITION: verify says the code reads something else.
    write(project / "catalog.yaml", CATALOG.replace("argument: side", "argument: POSITION"))
    checked = CliRunner().invoke(app, ["verify"])
    assert checked.exit_code == 1
    assert (
        "error AX903 SURVEY: argument POSITION is not read by dronebehaviors.survey:Survey, "
        "which reads SIDE" in checked.stdout
    )
    shutil.rmtree(project / "dronebehaviors")
    write(project / "pyproject.toml", '[tool.aeroexec]\nbehaviors = []\ncatalog = "catalog.yaml"\n')
    missing = CliRunner().invoke(app, ["behaviors"])
    assert missing.exit_code == 1
    assert missing.stdout.splitlines()[-1].endswith(
        "catalog.yaml: 1 behavior(s) without an implementation: SURVEY"
    )
