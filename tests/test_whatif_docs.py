"""docs/whatif.md's table of fault kinds is the registry's (aeroexec/vehicles/faults.py),
and the world file that lists them names every kind."""

from __future__ import annotations

from pathlib import Path

from aeroexec.vehicles.faults import KIND_NAMES, markdown_table
from aeroexec.vehicles.world import FAULTS_WORLD

DOC = Path(__file__).resolve().parent.parent / "docs" / "whatif.md"


def test_the_fault_table_is_the_registry() -> None:
    text = DOC.read_text(encoding="utf-8")
    start = text.index("<!-- fault-kinds:")
    table = text[text.index("\n", start) + 1 : text.index("<!-- end fault-kinds -->")]
    assert table == markdown_table(), "regenerate with aeroexec.vehicles.faults.markdown_table()"


def test_the_faults_world_documents_every_kind() -> None:
    comments = FAULTS_WORLD.read_text(encoding="utf-8")
    for kind in KIND_NAMES:
        assert f"#   {kind}" in comments
