"""The other commands on ROS 2 bags and their imports: `diff` of two imported
Aerostack2 flights (behavior timeline, outcomes, positions), `replay` of an Aerostack2
flight against a catalog given with --catalog (its timeline run open loop through the
executive), and the Foxglove layout's topics. (`info`: test_bags_ros2_real.py; `view`:
test_view_cli.py.)"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import as2_support
import pytest
from as2_support import FLIGHT, Run, write_flight
from mcap.reader import make_reader
from typer.testing import CliRunner

from aeroexec.bags import import_bag
from aeroexec.cli import app

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "as2"
CATALOG = FIXTURES / "catalog.yaml"
BEHAVIORS = FIXTURES / "behaviors.py"


def _invoke(*args: str | Path) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, [str(a) for a in args])
    return result.exit_code, result.stdout, result.stderr


@pytest.fixture(scope="module")
def flights(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("as2_commands")
    out = {}
    out["mcap_bag"] = write_flight(root / "mcap_bag", "mcap")
    out["sqlite3_bag"] = write_flight(root / "sqlite3_bag", "sqlite3")
    for name in ("mcap", "sqlite3"):
        out[name] = root / f"{name}.mcap"
        import_bag(out[f"{name}_bag"], out[name])
    return out


def test_diff_of_the_same_flight_in_both_storages_finds_nothing(flights: dict) -> None:
    code, out, err = _invoke("diff", flights["mcap"], flights["sqlite3"])
    assert code == 0, out + err
    assert "no differences (6 commands compared)" in out


def test_diff_finds_a_changed_outcome_and_position(
    flights: dict, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The same mission where the landing failed (ABORTED) and the vehicle stayed 1 m
    higher: diff names the outcome and the final position."""
    changed = tuple(
        Run(r.behavior, r.start_s, r.end_s, as2_support.ABORTED, False, r.paused)
        if r.behavior == "LandBehavior"
        else r
        for r in FLIGHT
    )
    monkeypatch.setattr(as2_support, "FLIGHT", changed)
    real_position = as2_support._position
    monkeypatch.setattr(
        as2_support, "_position", lambda t: (lambda p: (p[0], p[1], p[2] + 1.0))(real_position(t))
    )
    bag = write_flight(tmp_path / "failed_landing", "mcap")
    target = tmp_path / "failed.mcap"
    import_bag(bag, target)
    code, out, err = _invoke("diff", flights["mcap"], target, "-f", "json")
    assert code == 1, err
    messages = [d["message"] for d in json.loads(out)["differences"]]
    assert len(messages) == 2, messages
    (outcome,) = [m for m in messages if "LandBehavior" in m]
    assert "GOAL_ACHIEVED" in outcome and "WRONG_PROGRESS" in outcome
    (position,) = [m for m in messages if m.startswith("final vehicle state")]
    assert "(3.00, 3.00, 1.00)" in position and "1.00 m apart" in position


def test_replay_runs_the_timeline_against_the_given_catalog(flights: dict) -> None:
    """Aerostack2 has no catalog: replay checks its behavior timeline (activations with
    the goals as arguments, the operator's stop, each ending as recorded) against the
    one given. Everything but FollowPath's `path` fits the catalog; a list of points
    cannot be declared in a 2017-format catalog, so that activation is refused."""
    code, out, err = _invoke(
        "replay", flights["sqlite3_bag"], "--catalog", CATALOG, "-b", BEHAVIORS, "-f", "json"
    )
    assert code == 0, err
    (result,) = json.loads(out)["recordings"]
    assert result["recording"] == str(flights["sqlite3_bag"])
    assert result["compared_commands"] == 6  # 5 activations and the operator's stop
    differences = result["differences"]
    assert len(differences) == 1, differences
    assert "FollowPathBehavior" in json.dumps(differences[0])
    assert "path needs 3 numbers" in json.dumps(differences[0])
    assert any("behavior status" in note for note in result["notes"])


def test_replay_against_a_stricter_catalog_rejects_the_takeoff(
    flights: dict, tmp_path: Path
) -> None:
    strict = tmp_path / "strict.yaml"
    strict.write_text(
        CATALOG.read_text().replace(
            "argument: takeoff_height\n        allowed_values: [0, 10]",
            "argument: takeoff_height\n        allowed_values: [0, 1]",
        )
    )
    code, out, err = _invoke(
        "replay", flights["mcap_bag"], "--catalog", strict, "-b", BEHAVIORS, "--check"
    )
    assert code == 1, out + err
    assert "activate TakeoffBehavior" in out and "now rejected" in out
    assert "takeoff_height" in out


def test_the_foxglove_layout_shows_an_aerostack2_import(flights: dict, tmp_path: Path) -> None:
    """`layout --foxglove --drone drone0`: every aeroexec topic the layout's panels read
    is in the import (but the session log, which imports never have)."""

    layout = tmp_path / "layout.json"
    code, _, err = _invoke("layout", "--foxglove", "--drone", "drone0", "-o", layout)
    assert code == 0, err
    text = layout.read_text()
    with open(flights["mcap"], "rb") as stream:
        topics = {c.topic for c in make_reader(stream).get_summary().channels.values()}
    wanted = {t for t in topics if t.startswith("/drone0/") and f'"{t}' in text}
    assert {
        "/drone0/behavior_event",
        "/drone0/call_log",
        "/drone0/scene",
        "/drone0/vehicle/state",
    } <= wanted


def test_info_lists_the_imported_behavior_timeline(flights: dict) -> None:
    code, out, err = _invoke("info", flights["sqlite3"], "-f", "json")
    assert code == 0, err
    runs = [(r["behavior"], r["outcome"]) for r in json.loads(out)["behaviors"]]
    assert runs == [
        ("TakeoffBehavior", "GOAL_ACHIEVED"),
        ("GoToBehavior", "GOAL_ACHIEVED"),
        ("FollowPathBehavior", "WRONG_PROGRESS"),
        ("GoToBehavior", "INTERRUPTED"),
        ("LandBehavior", "GOAL_ACHIEVED"),
    ]
    code, out, err = _invoke("info", flights["sqlite3_bag"], "-f", "json")
    assert code == 0, err
    bag = json.loads(out)
    assert bag["profile"] == "ros2" and bag["complete"] is True
    assert bag["metadata"]["ros2_bag"]["format"] == "rosbag2 sqlite3"
    assert bag["channels"]["/drone0/TakeoffBehavior/_behavior/behavior_status"] == 270


def test_replay_of_a_folder_finds_its_ros2_bags(flights: dict, tmp_path: Path) -> None:
    """A folder of flights: a rosbag2 directory and a bare .db3 are recordings of it (the
    directory is one bag, not a folder to look into); a plain subdirectory and other
    files are not. A glob matches a rosbag2 directory too."""
    folder = tmp_path / "flights"
    folder.mkdir()
    shutil.copytree(flights["mcap_bag"], folder / "a_flight")
    (db3,) = flights["sqlite3_bag"].glob("*.db3")
    shutil.copy(db3, folder / "b_flight.db3")
    (folder / "c_notes").mkdir()
    (folder / "c_notes" / "x.mcap").write_bytes(b"not looked into")
    (folder / "d_readme.txt").write_text("not a recording")
    for argument in (folder, folder / "*_flight*"):
        code, out, err = _invoke(
            "replay", argument, "--catalog", CATALOG, "-b", BEHAVIORS, "-f", "json"
        )
        assert code == 0, err
        recordings = json.loads(out)["recordings"]
        assert [(r["recording"], r["compared_commands"]) for r in recordings] == [
            (str(folder / "a_flight"), 6),
            (str(folder / "b_flight.db3"), 6),
        ]


def test_check_reads_the_signals_an_aerostack2_import_carries(
    flights: dict, tmp_path: Path
) -> None:
    """`check` on an imported Aerostack2 flight: the vehicle (position, flying and armed
    from platform/info) and the behavior timeline are signals; what the import does not
    carry is `missing` with its reason, never guessed: the battery (no battery topic in
    the bag, so the import's default) and the capabilities (Aerostack2 has none)."""
    spec = tmp_path / "spec.yaml"
    spec.write_text(
        "properties:\n"
        "  - name: ceiling\n"
        "    formula: always(altitude <= 1.4)\n"
        "  - name: lands_after_takeoff\n"
        "    formula: always((active_TakeoffBehavior >= 1) implies "
        "eventually[0:30](active_LandBehavior >= 1))\n"
        "  - name: battery_floor\n"
        "    formula: always(battery >= 0.15)\n"
    )
    code, out, err = _invoke(
        "check", flights["sqlite3"], "--spec", "aeroexec:safety", "--spec", spec, "-f", "json"
    )
    assert code == 1, err  # the ceiling is broken
    (recording,) = json.loads(out)["recordings"]
    verdicts = {v["property"]: v for v in recording["verdicts"]}
    assert {name: v["status"] for name, v in verdicts.items()} == {
        "compatible_capabilities": "missing",
        "activations_answered": "held",  # every reconstructed activation has its event
        "ends_landed_disarmed": "held",  # platform/info: LANDED, then DISARMED
        "grounded_lands": "held",
        "ceiling": "violated",
        "lands_after_takeoff": "held",
        "battery_floor": "missing",
    }
    # 1.4 m is passed at 5.73 s on the way up (1.5 m at 6 s) and at 22.2 s on the way down
    interval = verdicts["ceiling"]["interval"]
    assert interval["start_s"] == pytest.approx(5.73, abs=0.15)
    assert interval["end_s"] == pytest.approx(22.2, abs=0.15)
    assert verdicts["battery_floor"]["missing"] == [
        {
            "signal": "battery",
            "why": "the recording's vehicle states lack battery (an import's default)",
        }
    ]
    assert verdicts["compatible_capabilities"]["missing"] == [
        {
            "signal": "incompatible",
            "why": "the recording has no list_of_active_capabilities messages",
        }
    ]
