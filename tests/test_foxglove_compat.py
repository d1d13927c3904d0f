"""Every channel of every recording aeroexec writes parses in Foxglove Studio 1.48 and
Lichtblick 1.10.8: `../shared/tools/foxglove-schema-check` runs both viewers' own
`parseJsonSchema` (bundled from their published code) under node. A schema they reject
hides its channel in the viewer (shown only under "Problems").

Recordings from `run`, `replay -o` (closed and open loop), `import` of a bag (the real
2017 Aerostack bag, and an Aerostack-style mission bag with reconstructed calls) and `fly`
(over MAVLink to `aeroexec mavsim`). Skipped, with the reason, when node or the tool is
not there (the tool is third-party code kept outside the repository).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import jsonschema
import pytest
from mcap.reader import make_reader
from test_bags_support import AEROSTACK_BAG, short_mission
from test_mavlink_flight import Proc, free_udp_port, start_mavsim, stop_mavsim, write_mission

from aeroexec.bags import import_bag
from aeroexec.mission import APPENDIX_C, SessionConfig, simulate
from aeroexec.mission.live import FlightConfig, fly
from aeroexec.recording.schemas import profile_schema_names, schema_document
from aeroexec.replay import Mode, ReplayOptions, replay_recording

ROOT = Path(__file__).resolve().parent.parent
TOOL = Path(
    os.environ.get("AEROEXEC_FOXGLOVE_CHECK", ROOT.parent / "shared/tools/foxglove-schema-check")
)
VIEWERS = ("lichtblick-1.10.8", "foxglove-studio-1.48")


def _missing() -> str | None:
    if shutil.which("node") is None:
        return "node is not installed (Debian package nodejs): cannot run the viewers' parsers"
    if not TOOL.is_file():
        return f"{TOOL} not found (set AEROEXEC_FOXGLOVE_CHECK to foxglove-schema-check)"
    return None


pytestmark = pytest.mark.skipif(_missing() is not None, reason=_missing() or "")


def _verdicts(output: str) -> dict[str, list[str]]:
    """schema name -> the per-viewer verdicts the tool printed."""
    out: dict[str, list[str]] = {}
    for line in output.splitlines():
        name, _, rest = line.partition(" ")
        out[name] = [part.strip() for part in rest.split("|")]
    return out


def _schemas_in(path: Path) -> set[str]:
    with open(path, "rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    return {s.name for s in summary.schemas.values() if s.encoding == "jsonschema"}


def check_recording(path: Path) -> dict[str, list[str]]:
    """Run the shared tool on `path`; every JSON schema in it must pass both parsers."""
    result = subprocess.run(
        [str(TOOL), str(path), sys.executable], capture_output=True, text=True, timeout=120
    )
    verdicts = _verdicts(result.stdout)
    assert result.returncode == 0, result.stdout + result.stderr
    assert set(verdicts) == _schemas_in(path)  # every schema was checked
    for name, parts in verdicts.items():
        assert parts == [f"{viewer}: ok" for viewer in VIEWERS], (name, parts)
    return verdicts


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("foxglove")


@pytest.fixture(scope="module")
def run_recording(folder: Path) -> Path:
    path = folder / "run.mcap"
    simulate(SessionConfig(mission=APPENDIX_C, record=path))
    return path


def test_every_profile_schema_parses_in_both_viewers(folder: Path) -> None:
    """All the profile's schemas, also those a given recording may not use."""
    schemas = folder / "schemas.json"
    schemas.write_text(json.dumps({name: schema_document(name) for name in profile_schema_names()}))
    script = TOOL.with_name("foxglove-schema-check.js")
    result = subprocess.run(
        ["node", str(script), str(schemas)], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stdout + result.stderr
    verdicts = _verdicts(result.stdout)
    assert set(verdicts) == set(profile_schema_names())
    assert all(parts == [f"{v}: ok" for v in VIEWERS] for parts in verdicts.values())


def test_the_tool_rejects_what_the_viewers_reject(folder: Path) -> None:
    """The check can fail: the schemas of the first release are refused, as reported."""
    old = ROOT / "recordings" / "appendix_c-v0.1.0.mcap"
    result = subprocess.run(
        [str(TOOL), str(old), sys.executable], capture_output=True, text=True, timeout=120
    )
    verdicts = _verdicts(result.stdout)
    assert result.returncode == 1
    assert "Unsupported type" in " ".join(verdicts["aeroexec.ServiceCall"])
    assert all("FAIL" in part for part in verdicts["aeroexec.BehaviorEvent"])


def test_run(run_recording: Path) -> None:
    verdicts = check_recording(run_recording)
    assert {
        "aeroexec.ServiceCall",
        "aeroexec.MissionCommand",
        "aeroexec.BehaviorEvent",
        "foxglove.FrameTransform",
        "foxglove.SceneUpdate",
        "foxglove.Log",
    } <= set(verdicts)


@pytest.mark.parametrize("mode", [Mode.closed, Mode.open])
def test_replay_output(run_recording: Path, folder: Path, mode: Mode) -> None:
    out = folder / f"replay-{mode.value}.mcap"
    result = replay_recording(run_recording, ReplayOptions(mode=mode, output=str(out)))
    assert result.error is None and result.equal
    assert "aeroexec.ServiceCall" in check_recording(out)


def test_import_of_the_real_aerostack_bag(folder: Path) -> None:
    out = folder / "aerostack.mcap"
    import_bag(AEROSTACK_BAG, out)
    assert "foxglove.FrameTransform" in check_recording(out)


def test_import_of_a_mission_bag_with_reconstructed_calls(folder: Path) -> None:
    bag = short_mission().write(folder / "mission.bag")
    out = folder / "mission.mcap"
    import_bag(bag, out)
    verdicts = check_recording(out)
    assert {"aeroexec.ServiceCall", "aeroexec.MissionCommand", "aeroexec.BehaviorEvent"} <= set(
        verdicts
    )
    # and the strict side: every derived message validates against its schema
    declared: set[str] = set()
    with open(out, "rb") as stream:
        for schema, channel, message in make_reader(stream).iter_messages():
            if channel.message_encoding == "json":
                assert schema is not None
                document = json.loads(schema.data)
                data = json.loads(message.data)
                jsonschema.validate(data, document)
                declared |= set(data) & set(document["properties"])
    assert {"reconstructed", "evidence"} <= declared  # the importer's own fields are declared


@pytest.fixture
def procs() -> Iterator[list[Proc]]:
    started: list[Proc] = []
    yield started
    for proc in started:
        proc.kill()


def test_fly(tmp_path: Path, procs: list[Proc]) -> None:
    port = free_udp_port()
    stats = tmp_path / "mavsim.json"
    mavsim = start_mavsim(procs, port, stats)
    mission = write_mission(
        tmp_path,
        "    return [api.executeBehavior('TAKE_OFF'), api.executeBehavior('LAND')]\n",
    )
    out = tmp_path / "fly.mcap"
    result = fly(FlightConfig(mission=mission, connect=f"udpin:127.0.0.1:{port}", record=out))
    stop_mavsim(mavsim, stats)
    assert result.outcome.value == ["GOAL_ACHIEVED", "GOAL_ACHIEVED"]
    verdicts = check_recording(out)
    assert {"aeroexec.ServiceCall", "aeroexec.Topic", "foxglove.FrameTransform"} <= set(verdicts)
