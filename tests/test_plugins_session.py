"""Sessions with a developer's behaviors: no silent stand-ins, which code ran in the
recording (deterministically), code changes in replay, argument spelling, the mission's
own directory."""

from __future__ import annotations

import json
import shutil
import sys
import textwrap
from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.catalog import DEFAULT_CATALOG, load_catalog
from aeroexec.catalog.loader import parse_catalog
from aeroexec.cli import app
from aeroexec.errors import BehaviorError
from aeroexec.executive import Executive, GenericBehavior
from aeroexec.mission import SessionConfig, simulate
from aeroexec.plugins import BehaviorSources, CodeEntry, code_changes
from aeroexec.plugins.manifest import METADATA_NAME
from aeroexec.recording import open_recording
from aeroexec.recording.info import CODE_RECORD, recording_info
from aeroexec.replay import ReplayOptions, replay_recording

SURVEY_CATALOG = DEFAULT_CATALOG.read_text(encoding="utf-8").replace(
    "behavior_lists:",
    """\
  - behavior: SURVEY
    timeout: 60
    recurrent: no
    arguments:
      - argument: side
        allowed_values: [1, 10]

  - behavior: INSPECT
    timeout: 30
    recurrent: no

behavior_lists:""",
    1,
)

SURVEY = """\
import math

from aeroexec.executive import Behavior, Finished, Situation


class Survey(Behavior):
    name = "SURVEY"
    argument_names = ("SIDE",)
    reach = 0.2

    def check_situation(self, beliefs):
        return Situation.ok_if(beliefs.holds("flying(self)"), "not flying")

    def on_start(self, args):
        side = float(args["SIDE"])
        x, y, z = self.vehicle.state().position
        self.corners = [(x + side, y, z), (x, y, z)]
        self.vehicle.go_to(*self.corners[0])

    def on_run(self):
        if math.dist(self.vehicle.state().position, self.corners[0]) <= self.reach:
            self.corners.pop(0)
            if not self.corners:
                return Finished(detail="surveyed")
            self.vehicle.go_to(*self.corners[0])
        return None
"""

#: The same catalog and mission without INSPECT (every behavior implemented).
COMPLETE_CATALOG = SURVEY_CATALOG.replace(
    "  - behavior: INSPECT\n    timeout: 30\n    recurrent: no\n\n", ""
)

MISSION = """\
import executive_engine_api as api


def runMission():
    api.executeBehavior('TAKE_OFF')
    api.executeBehavior('SURVEY', side=2)
    api.executeBehavior('INSPECT')
    api.executeBehavior('GO_TO_POINT', coordinates=[1, 0, 1])
    api.executeBehavior('LAND')
"""


COMPLETE_MISSION = MISSION.replace("    api.executeBehavior('INSPECT')\n", "")


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


@pytest.fixture
def project(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A project with SURVEY implemented and INSPECT not, configured in pyproject.toml."""
    root = tmp_path / "project"
    write(
        root / "pyproject.toml", '[tool.aeroexec]\nbehaviors = ["survey.py"]\ncatalog = "c.yaml"\n'
    )
    write(root / "survey.py", SURVEY)
    write(root / "c.yaml", SURVEY_CATALOG)
    write(root / "mission.py", MISSION)
    monkeypatch.chdir(root)
    return root


def invoke(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, list(args))
    return result.exit_code, result.stdout, result.stderr


def test_a_catalog_behavior_without_code_is_refused_with_names_and_places(project: Path) -> None:
    code, out, err = invoke("run", "mission.py", "-o", "out.mcap")
    assert code == 2
    (line,) = err.strip().splitlines()
    row = SURVEY_CATALOG.splitlines().index("  - behavior: INSPECT") + 1
    assert line.startswith(f"{project / 'c.yaml'}:{row}:5: error: no implementation for INSPECT ")
    assert "pyproject.toml [tool.aeroexec] behaviors (survey.py)" in line
    assert "the standard library" in line and "--allow-unimplemented" in line
    assert out == "" and not (project / "out.mcap").exists()  # nothing ran, nothing written


def test_allowed_stand_ins_are_announced_once_and_marked_in_the_recording(project: Path) -> None:
    code, out, err = invoke("run", "mission.py", "-o", "out.mcap", "--allow-unimplemented")
    assert code == 0, err
    assert err.splitlines() == [
        "warning: INSPECT has no implementation: a stand-in (GenericBehavior) ends it with "
        "GOAL_ACHIEVED after 1 s"
    ]
    assert "5 activations: 5 GOAL_ACHIEVED" in out
    recording = open_recording(project / "out.mcap")
    assert recording.metadata["aeroexec"]["stand_ins"] == "INSPECT"
    code_record = recording.metadata[METADATA_NAME]
    inspect = CodeEntry.parse(code_record["INSPECT"])
    assert inspect.stand_in and inspect.reference == "aeroexec.executive.behavior:GenericBehavior"
    assert CodeEntry.parse(code_record["SURVEY"]).reference == "survey:Survey"
    assert recording.attachment("behaviors/survey.py").text == SURVEY
    # A replay keeps the recorded stand-in (and says nothing changed).
    result = replay_recording(
        project / "out.mcap",
        ReplayOptions(behaviors=BehaviorSources(("survey.py",), str(project), entry_points=False)),
    )
    assert result.error is None and result.equal and result.code_changes == ()


def test_recordings_say_which_code_ran_and_are_the_same_bytes_from_any_folder(
    project: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    write(project / "c.yaml", COMPLETE_CATALOG)
    write(project / "mission.py", COMPLETE_MISSION)
    copy = tmp_path / "elsewhere" / "deeper" / "copy"
    shutil.copytree(project, copy)
    for root in (project, copy):
        monkeypatch.chdir(root)
        code, _, err = invoke("run", "mission.py", "-o", "out.mcap", "-q")
        assert code == 0, err
    first = (project / "out.mcap").read_bytes()
    assert first == (copy / "out.mcap").read_bytes()
    assert str(tmp_path).encode() not in first
    info = recording_info(project / "out.mcap")
    assert CODE_RECORD == METADATA_NAME
    assert info.metadata[CODE_RECORD]["SURVEY"].startswith("survey:Survey sha256:")
    text = info.to_text()
    assert "code:" in text and "  SURVEY " in text
    assert "attachment:  behaviors/survey.py (text/x-python" in text


def test_replay_with_changed_code_reports_it_beside_the_differences(project: Path) -> None:
    write(project / "c.yaml", COMPLETE_CATALOG)
    write(project / "mission.py", COMPLETE_MISSION)
    code, _, err = invoke("run", "mission.py", "-o", "base.mcap", "-q")
    assert code == 0, err
    code, out, err = invoke("replay", "base.mcap", "--check")
    assert code == 0, out + err
    assert "code changed" not in out
    write(project / "survey.py", SURVEY.replace("reach = 0.2", "reach = 0.01"))
    code, out, err = invoke("replay", "base.mcap", "--check")
    assert code == 1, out + err
    lines = out.splitlines()
    assert lines[0].endswith("; code changed")
    assert "SURVEY" in lines[1] and "now ends GOAL_ACHIEVED after" in lines[1]
    assert [line for line in lines if line.startswith("  code changed: ")] == [lines[-1]]
    assert lines[-1].startswith("  code changed: SURVEY: survey:Survey source changed (sha256:")
    code, out, err = invoke("replay", "base.mcap", "--format", "json")
    (changed,) = json.loads(out)["recordings"][0]["code_changes"]
    assert changed.startswith("SURVEY: survey:Survey source changed")


def test_code_changes_compare_class_source_and_stand_ins() -> None:
    recorded = {
        "A": "m:A sha256:1111",
        "B": "m:B sha256:2222",
        "C": "stand-in aeroexec.executive.behavior:GenericBehavior sha256:3333",
        "D": "m:D sha256:4444",
        "GONE": "m:G sha256:5555",
    }
    current = {
        "A": "m:A sha256:1111",
        "B": "m:B sha256:9999",
        "C": "m:C sha256:3333",
        "D": "other:D sha256:4444",
    }
    assert code_changes(recorded, current) == (
        "B: m:B source changed (sha256:2222 -> 9999)",
        "C: implemented by m:C (was a stand-in)",
        "D: m:D -> other:D",
    )


def test_the_executive_takes_its_library_and_refuses_gaps_without_a_stand_in() -> None:
    catalog = parse_catalog(
        "behavior_descriptors:\n  - behavior: SURVEY\n    timeout: 5\n    recurrent: no\n"
        "behavior_lists: []\ncapability_descriptors: []\n",
        "mini.yaml",
    )
    with pytest.raises(BehaviorError, match="no implementation for SURVEY"):
        Executive(catalog, library={})
    executive = Executive(catalog, library={}, stand_in=GenericBehavior)
    assert type(executive.behaviors["SURVEY"]) is GenericBehavior
    import aeroexec.executive.executive as module

    assert "aeroexec.behaviors" not in Path(module.__file__).read_text(encoding="utf-8")


def test_catalog_argument_spelling_reaches_the_declared_names(tmp_path: Path) -> None:
    """Real catalogs spell `coordinates`; the standard GO_TO_POINT reads `COORDINATES`."""
    lower = DEFAULT_CATALOG.read_text(encoding="utf-8").replace(
        "argument: COORDINATES", "argument: coordinates"
    )
    catalog = write(tmp_path / "lower.yaml", lower)
    assert load_catalog(catalog).behaviors["GO_TO_POINT"].arguments[0].name == "coordinates"
    mission = write(
        tmp_path / "m.py",
        "import executive_engine_api as api\n\ndef runMission():\n"
        "    api.executeBehavior('TAKE_OFF')\n"
        "    return api.executeBehavior('GO_TO_POINT', coordinates=[1, 1, 1])\n",
    )
    result = simulate(SessionConfig(mission=mission, catalog=catalog))
    assert result.outcome.value == "GOAL_ACHIEVED", result.activations[-1]
    assert result.final_state.position[0] == pytest.approx(1.0, abs=0.05)


def test_the_mission_directory_is_importable_only_while_it_runs(tmp_path: Path) -> None:
    write(tmp_path / "route.py", "WAYPOINT = [2, 0, 1]\n")
    mission = write(
        tmp_path / "m.py",
        "import executive_engine_api as api\nfrom route import WAYPOINT\n\n"
        "def runMission():\n    api.executeBehavior('TAKE_OFF')\n"
        "    return api.executeBehavior('GO_TO_POINT', coordinates=WAYPOINT)\n",
    )
    before = list(sys.path)
    result = simulate(SessionConfig(mission=mission))
    assert result.outcome.returned and result.outcome.value == "GOAL_ACHIEVED"
    assert sys.path == before
    assert "route" not in sys.modules  # the next run imports it afresh
    write(tmp_path / "route.py", "WAYPOINT = [0, 2, 1]\n")
    again = simulate(SessionConfig(mission=mission))
    assert again.final_state.position[1] == pytest.approx(2.0, abs=0.05)


def test_replay_refuses_a_behavior_whose_code_is_gone(project: Path) -> None:
    write(project / "c.yaml", COMPLETE_CATALOG)
    write(project / "mission.py", COMPLETE_MISSION)
    assert invoke("run", "mission.py", "-o", "base.mcap", "-q")[0] == 0
    write(project / "pyproject.toml", "[tool.aeroexec]\nbehaviors = []\n")
    code, out, err = invoke("replay", "base.mcap")
    assert code == 2, out
    (line,) = err.strip().splitlines()
    assert line.startswith("base.mcap: error: ") and "no implementation for SURVEY" in line
    code, out, err = invoke("replay", "base.mcap", "-b", "no_behaviors_here.py")
    assert code == 2
    assert err.strip() == (
        "aeroexec replay: error: --behaviors no_behaviors_here.py: no such file or directory: "
        "no_behaviors_here.py"
    )


def test_fly_refuses_before_the_link_opens(project: Path) -> None:
    code, out, err = invoke("fly", "mission.py", "--connect", "udpin:127.0.0.1:9", "-o", "x.mcap")
    assert code == 2
    assert "error: no implementation for INSPECT" in err and len(err.strip().splitlines()) == 1
    assert "waiting for a heartbeat" not in out and not (project / "x.mcap").exists()


def test_behaviors_lists_sources_and_what_the_catalog_lacks(project: Path) -> None:
    code, out, err = invoke("behaviors")
    assert code == 1, err
    rows = {line.split()[0]: line for line in out.splitlines() if line and line[0].isupper()}
    assert "survey:Survey" in rows["SURVEY"] and "survey.py:" in rows["SURVEY"]
    assert "pyproject.toml (survey.py)" in rows["SURVEY"]
    assert "aeroexec.behaviors.flight:TakeOff" in rows["TAKE_OFF"]
    assert "standard library" in rows["TAKE_OFF"]
    assert out.splitlines()[-2].startswith("looked in: pyproject.toml [tool.aeroexec] behaviors")
    assert out.splitlines()[-1].endswith("c.yaml: 1 behavior(s) without an implementation: INSPECT")
    code, out, _ = invoke("behaviors", "--catalog", str(DEFAULT_CATALOG))
    assert code == 0 and out.splitlines()[-1].endswith("every behavior has an implementation")
    survey = next(line for line in out.splitlines() if line.startswith("SURVEY "))
    assert survey.endswith("(not in the catalog)")
