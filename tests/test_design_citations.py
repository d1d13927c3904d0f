"""The repository's design document is `docs/design.md`, and every citation of it, in
code, tests, benchmarks and docs, names it there and names a section it has (issue 19)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DESIGN = ROOT / "docs" / "design.md"
SOURCES = sorted(
    [
        ROOT / "README.md",
        *(ROOT / "docs").glob("*.md"),
        *(ROOT / "aeroexec").rglob("*.py"),
        *(ROOT / "tests").glob("*.py"),
        *(ROOT / "benchmarks").glob("*.py"),
        *(ROOT / "benchmarks").glob("*.md"),
    ]
)


def anchor(heading: str) -> str:
    """The anchor GitHub gives a heading: lower case, punctuation dropped, spaces as '-'."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def design_anchors() -> set[str]:
    text = DESIGN.read_text(encoding="utf-8")
    text = re.sub(r"```.*?```", "", text, flags=re.DOTALL)  # no headings in code blocks
    return {anchor(m[1]) for m in re.finditer(r"^#{1,6} (.+)$", text, re.MULTILINE)}


def citations() -> list[tuple[str, int, str, str]]:
    """(file, line, how it is named, section or '') for every mention of design.md."""
    found = []
    for path in SOURCES:
        if path == DESIGN or path == Path(__file__):
            continue
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            for match in re.finditer(r"([\w./-]*)design\.md(#[\w-]+)?", line):
                name = f"{match[1]}design.md"
                found.append((str(path.relative_to(ROOT)), number, name, match[2] or ""))
    return found


CITATIONS = citations()


def test_the_design_document_is_in_the_repository() -> None:
    anchors = design_anchors()
    for section in (
        "architecture",
        "how-a-session-is-composed",
        "the-repairs-of-the-thesis",
        "determinism",
        "guarantees",
        "nothing-runs-by-surprise",
        "behavior-integration",
        "the-verifiers-models",
        "replay",
        "fleet-replay",
        "performance-targets",
        "where-this-departs-from-the-original-brief",
    ):
        assert section in anchors, section
    # It links the recording profile and the benchmarks instead of repeating them.
    text = DESIGN.read_text(encoding="utf-8")
    assert "(recording.md)" in text and "(../benchmarks/README.md)" in text


def test_code_tests_benchmarks_and_docs_cite_it() -> None:
    cited_from = {file.split("/")[0] for file, *_ in CITATIONS}
    assert {"aeroexec", "tests", "benchmarks", "docs", "README.md"} <= cited_from


@pytest.mark.parametrize(("file", "line", "name", "section"), CITATIONS)
def test_every_citation_names_docs_design_md_and_a_section_it_has(
    file: str, line: int, name: str, section: str
) -> None:
    where = f"{file}:{line}"
    in_docs = file.startswith("docs/")
    # From docs/, a link is relative (`design.md#...`); from anywhere else, `docs/...`.
    assert name == ("design.md" if in_docs else "docs/design.md"), f"{where}: cites {name}"
    if section:
        assert section[1:] in design_anchors(), f"{where}: docs/design.md has no {section}"
    else:
        # The document as a whole may be linked from the README; code cites a section.
        assert file == "README.md", f"{where}: cite a section (docs/design.md#...)"


def test_no_citation_by_section_number() -> None:
    for path in SOURCES:
        text = path.read_text(encoding="utf-8")
        assert not re.search(r"design\.md,? (section|s\.|§) ?\d", text), path
