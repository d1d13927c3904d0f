"""Open-loop replay of Aerostack-style bags against the thesis' Appendix A catalog and
edited copies of it: `replay_recording` and `aeroexec replay BAG` take the bag itself.

The bag (tests/test_bags_support.py `short_mission`) is what a 2017 Aerostack drone flying
that catalog would record; its commands exist only as reconstructions from the active
list. With the unchanged catalog the executive must decide exactly what the bag shows;
with each edit, exactly the consequences of the edit must be reported.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from test_bags_support import THESIS_CATALOG, TURTLE_BZ2, short_mission
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.recording import open_recording
from aeroexec.replay import ReplayOptions, ReplayResult, replay_recording

#: Edits of catalog/aerostack-2017.yaml (old text, new text).
EDITS: dict[str, list[tuple[str, str]]] = {
    # GO_TO_POINT must now succeed within 2 s (the flight took 3.6 s).
    "short_timeout": [
        ("  - behavior: GO_TO_POINT\n    timeout: 120", "  - behavior: GO_TO_POINT\n    timeout: 2")
    ],
    # LAND no longer conflicts with the motion behaviors (KEEP_HOVERING among them).
    "land_compatible": [
        (
            "  - behavior: LAND\n    timeout: 15\n    recurrent: no\n"
            "    incompatible_lists: [motion_behaviors, rotation_behaviors]",
            "  - behavior: LAND\n    timeout: 15\n    recurrent: no\n"
            "    incompatible_lists: [rotation_behaviors]",
        ),
        ("      - TAKE_OFF\n      - LAND\n", "      - TAKE_OFF\n"),
    ],
    # PAY_ATTENTION removed from the catalog.
    "no_pay_attention": [
        (
            "  - behavior: PAY_ATTENTION\n    recurrent: yes\n"
            "    capabilities: [VISUAL_MARKERS_RECOGNITION]\n",
            "",
        )
    ],
}


def edited(folder: Path, name: str) -> Path:
    text = THESIS_CATALOG.read_text()
    for old, new in EDITS[name]:
        assert old in text, f"catalog/aerostack-2017.yaml changed: update EDITS[{name!r}]"
        text = text.replace(old, new)
    path = folder / f"{name}.yaml"
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("bag_replay")


@pytest.fixture(scope="module")
def bag(folder: Path) -> Path:
    return short_mission().write(folder / "mission.bag")


def replay(bag: Path, catalog: Path, **options: object) -> ReplayResult:
    result = replay_recording(bag, ReplayOptions(catalog=str(catalog), **options))  # type: ignore[arg-type]
    assert result.error is None, result.error
    assert result.diff is not None
    return result


def found(result: ReplayResult) -> list[tuple[int | None, str, str]]:
    assert result.diff is not None
    return [(d.command, d.kind, d.message) for d in result.diff.differences]


@pytest.mark.parametrize("version", ["2018", "2017"])
def test_the_unchanged_catalog_decides_what_the_bag_shows(folder: Path, version: str) -> None:
    path = short_mission(version=version).write(folder / f"unchanged_{version}.bag")
    result = replay(path, THESIS_CATALOG)
    assert result.mode == "open"
    assert result.recording == str(path)  # the bag, not the temporary import
    assert result.diff is not None and result.diff.compared == 6
    assert found(result) == []
    assert any("6 of the recorded commands were reconstructed" in n for n in result.notes)


def test_a_shorter_timeout_ends_the_flight_early(folder: Path, bag: Path) -> None:
    result = replay(bag, edited(folder, "short_timeout"))
    assert found(result) == [
        (
            2,
            "end_event",
            "#2 activate GO_TO_POINT coordinates=[1, 2, 1] now ends TIME_OUT after 2.0 s "
            "(was GOAL_ACHIEVED after 3.6 s): no result within 2 s",
        )
    ]


def test_a_compatible_land_no_longer_preempts_hovering(folder: Path, bag: Path) -> None:
    result = replay(bag, edited(folder, "land_compatible"))
    assert [(c, k) for c, k, _ in found(result)] == [
        (3, "end_event"),
        (5, "preemptions"),
        (5, "capabilities"),
        (5, "processes"),
    ]
    messages = [m for _, _, m in found(result)]
    assert messages[0] == (
        "#3 activate KEEP_HOVERING now ends still active at the end (was INTERRUPTED after 3.5 s)"
    )
    assert messages[1] == "#5 activate LAND no longer preempts KEEP_HOVERING"
    assert "no longer releases SETPOINT_BASED_FLIGHT_CONTROL" in messages[2]
    assert "no longer stops droneTrajectoryController" in messages[3]


def test_a_removed_behavior_is_rejected_and_cannot_be_inhibited(folder: Path, bag: Path) -> None:
    result = replay(bag, edited(folder, "no_pay_attention"))
    assert found(result) == [
        (1, "accepted", "#1 activate PAY_ATTENTION now rejected: unknown behavior PAY_ATTENTION"),
        (4, "accepted", "#4 inhibit PAY_ATTENTION now rejected: PAY_ATTENTION is not active"),
    ]


def test_the_replay_of_a_bag_can_be_recorded(folder: Path, bag: Path) -> None:
    target = folder / "replayed.mcap"
    replay(bag, THESIS_CATALOG, output=str(target))
    recording = open_recording(target)
    assert recording.complete
    assert recording.metadata["aeroexec"]["replay_mode"] == "open"
    calls = [r for r in recording.records() if r.topic == "/drone1/activate_behavior"]
    assert [c.request["behavior"] for c in calls] == [  # type: ignore[union-attr]
        "TAKE_OFF",
        "PAY_ATTENTION",
        "GO_TO_POINT",
        "KEEP_HOVERING",
        "LAND",
    ]


# -- the command line ------------------------------------------------------------------------
def _invoke(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, list(args))
    return result.exit_code, result.stdout, result.stderr


def test_cli_replay_of_a_bag_with_check(folder: Path, bag: Path) -> None:
    code, out, err = _invoke("replay", str(bag), "--catalog", str(THESIS_CATALOG), "--check")
    assert (code, err) == (0, "")
    assert "no differences (6 commands compared)" in out
    changed = edited(folder, "short_timeout")
    code, out, _ = _invoke(
        "replay", str(bag), "--catalog", str(changed), "--check", "--format", "json"
    )
    assert code == 1
    report = json.loads(out)["recordings"][0]
    assert report["recording"] == str(bag)
    assert [d["kind"] for d in report["differences"]] == ["end_event"]


def test_cli_replay_of_a_bag_without_a_catalog_names_the_bag(bag: Path) -> None:
    code, out, err = _invoke("replay", str(bag))
    assert code == 2 and out == ""
    assert (
        err
        == f"{bag}: error: the recording has no catalog.yaml attachment: give one with --catalog\n"
    )


def test_cli_replay_of_a_bag_without_behavior_topics(tmp_path: Path) -> None:
    code, _, err = _invoke("replay", str(TURTLE_BZ2), "--catalog", str(THESIS_CATALOG))
    assert code == 2
    assert err.startswith(f"{TURTLE_BZ2}: error: no behavior commands to replay")
    assert err.count("\n") == 1 and "Traceback" not in err


def test_a_bag_without_resource_topics_compares_what_it_has(folder: Path) -> None:
    """Most bags carry no capability lists or process heartbeats: the replayed
    executive's transitions must not show up as differences, and the report says what
    was not compared."""
    path = short_mission(resources=False).write(folder / "no_resources.bag")
    result = replay(path, THESIS_CATALOG)
    assert found(result) == []
    notes = result.diff.notes if result.diff else ()
    assert any("no capabilities transitions: capabilities not compared" in n for n in notes)
    assert any("no processes transitions: processes not compared" in n for n in notes)
    # what the bag does hold is still compared
    changed = replay(path, edited(folder, "short_timeout"))
    assert [kind for _, kind, _ in found(changed)] != []
