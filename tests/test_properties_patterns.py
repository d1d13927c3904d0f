"""docs/properties.md's ten specification patterns (Menghi et al., TSE 2019), each checked
on real recordings of `aeroexec run`: the table says where each holds and where it is
violated, and this test reads the table."""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

import pytest
from test_properties import PATROL

from aeroexec.mission.session import SessionConfig, simulate
from aeroexec.properties.check import HELD, VIOLATED, check_recording
from aeroexec.properties.signals import FAMILIES, SIGNALS
from aeroexec.properties.spec import parse_properties
from aeroexec.vehicles.world import DEFAULT_WORLD

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "properties.md"
APPENDIX_C = ROOT / "missions" / "appendix_c.py"


def _section(title: str) -> str:
    text = DOC.read_text(encoding="utf-8")
    start = text.index(f"\n## {title}\n")
    end = text.find("\n## ", start + 1)
    return text[start:end]


def _rows(section: str) -> list[list[str]]:
    rows = [
        [cell.strip() for cell in line.strip().strip("|").split(" | ")]
        for line in section.splitlines()
        if line.startswith("| ") and not line.startswith("| ---")
    ]
    return rows[1:]


def _names(cell: str) -> list[str]:
    return [n.strip() for n in cell.split(",") if n.strip()]


PATTERNS = [
    (row[0], row[1].strip("`"), _names(row[2]), _names(row[3]))
    for row in _rows(_section("Ten patterns from robotic missions"))
]


def _simulate(tmp: Path, name: str, mission: Path | str, world: Path | None = None) -> Path:
    if isinstance(mission, str):
        (tmp / f"{name}.py").write_text(mission, encoding="utf-8")
        mission = tmp / f"{name}.py"
    out = tmp / f"{name}.mcap"
    with contextlib.redirect_stdout(io.StringIO()):
        simulate(SessionConfig(mission=mission, world=world, record=out))
    return out


@pytest.fixture(scope="module")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    tmp = tmp_path_factory.mktemp("patterns")
    world = tmp / "low_battery.yaml"
    world.write_text(
        DEFAULT_WORLD.read_text(encoding="utf-8").replace(
            "failures: []", "failures:\n  - {kind: low_battery, at: 10.0, level: 15}"
        ),
        encoding="utf-8",
    )
    return {
        "appendix_c": _simulate(tmp, "appendix_c", APPENDIX_C),
        "patrol": _simulate(tmp, "patrol", PATROL),
        "low_battery": _simulate(tmp, "low_battery", APPENDIX_C, world),
    }


def _verdict(path: Path, formula: str):
    props = parse_properties(f"properties:\n  - name: p\n    formula: '{formula}'\n", "p.yaml")
    [verdict] = check_recording(path, props).verdicts
    return verdict


def test_the_table_has_ten_patterns() -> None:
    assert len(PATTERNS) == 10
    assert all(holds for _, _, holds, _ in PATTERNS)


@pytest.mark.parametrize(("pattern", "formula", "holds", "violated"), PATTERNS)
def test_each_pattern_holds_and_fails_where_the_table_says(
    recordings, pattern, formula, holds, violated
) -> None:
    for name in holds:
        assert _verdict(recordings[name], formula).status == HELD, (pattern, name)
    for name in violated:
        assert _verdict(recordings[name], formula).status == VIOLATED, (pattern, name)


def test_tightened_bounds_are_violated_when_the_doc_says(recordings) -> None:
    land = _verdict(
        recordings["appendix_c"],
        "always((command_LAND >= 1) implies eventually[0:2](landed >= 1))",
    )
    assert land.status == VIOLATED and land.interval_s[0] == pytest.approx(15.6)
    battery = _verdict(
        recordings["low_battery"],
        "always((fault_low_battery >= 1) implies eventually[0:5](landed >= 1))",
    )
    assert battery.status == VIOLATED and battery.interval_s[0] == pytest.approx(10.0)


def test_the_signal_table_is_the_code() -> None:
    rows = _rows(_section("Signals"))
    documented = {row[0].strip("`"): row[1:] for row in rows}
    expected = {s.name: [s.unit, s.meaning, s.source] for s in SIGNALS}
    for prefix, (unit, meaning, source) in FAMILIES.items():
        [name] = [n for n in documented if n.startswith(prefix)]
        expected[name] = [unit, meaning, source]
    assert documented == expected


def test_the_builtin_table_is_the_builtin_file() -> None:
    from aeroexec.properties.spec import load_properties

    section = _section("The built-in set: aeroexec:safety")
    rows = {r[0].strip("`"): r[1].strip("`") for r in _rows(section)}
    builtin = {p.name: p.formula.text for p in load_properties(["aeroexec:safety"]).properties}
    assert rows == builtin
    assert re.search(r"eventually\[0:land_within_s\]", rows["grounded_lands"])
    assert "`land_within_s` (30 s)" in section
