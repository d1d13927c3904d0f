"""Run the verifier: read catalogs and missions, apply every rule, build the report."""

from __future__ import annotations

import glob
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from aeroexec.catalog.loader import read_catalog
from aeroexec.catalog.model import Catalog
from aeroexec.errors import CatalogError, Mark
from aeroexec.verifier.findings import Finding, Report
from aeroexec.verifier.graphs import CatalogGraphs
from aeroexec.verifier.missions import (
    MissionScript,
    check_mission,
    expand_mission_paths,
    read_mission,
)
from aeroexec.verifier.registry import catalog_checks, code_checks
from aeroexec.verifier.witness_run import realize_findings

if TYPE_CHECKING:
    from aeroexec.plugins.discovery import BehaviorSet

CatalogInput = str | Path | Catalog


def expand_catalog_paths(patterns: Iterable[str | Path]) -> list[str]:
    """Catalog paths as given; glob patterns that name no existing file (quoted on the
    command line, or on Windows) are expanded here. `CatalogError` for a pattern that
    matches nothing; a plain missing path is left for the loader to report."""
    result: list[str] = []
    for pattern in patterns:
        text = str(pattern)
        if Path(text).exists() or not glob.has_magic(text):
            result.append(text)
            continue
        matches = sorted(glob.glob(text, recursive=True))
        if not matches:
            raise CatalogError("no catalog matches this pattern", Mark(text))
        result.extend(matches)
    return result


def check_catalog(
    catalog: Catalog,
    codes: Iterable[str] | None = None,
    behaviors: BehaviorSet | None = None,
) -> list[Finding]:
    """The loader's diagnostics plus every catalog rule's findings (unsorted).

    `codes` restricts the rules that run (loader diagnostics always pass through).
    With `behaviors` (the implementations the project runs), the catalog is checked
    against them too (AX9xx).
    """
    wanted = None if codes is None else set(codes)
    findings = [Finding.from_diagnostic(d) for d in catalog.diagnostics]
    graphs = CatalogGraphs(catalog)
    for rule in catalog_checks():
        if wanted is not None and rule.code not in wanted:
            continue
        assert rule.check is not None
        findings.extend(rule.check(graphs))  # type: ignore[call-arg]  (a catalog rule)
    if behaviors is not None:
        for rule in code_checks():
            if wanted is None or rule.code in wanted:
                findings.extend(rule.check(graphs, behaviors))  # type: ignore[call-arg]
        # Witnesses as the real behaviors make them happen (TAKE_OFF first, ...).
        findings = realize_findings(catalog, findings, behaviors.library())
    return findings


def verify_catalog(catalog: Catalog) -> Report:
    """Verify one loaded catalog."""
    return Report(tuple(check_catalog(catalog)), catalogs=(catalog.source,))


def verify_catalog_file(path: str | Path) -> Report:
    """Read (leniently) and verify one catalog file; `CatalogError` if unreadable."""
    return verify_catalog(read_catalog(path))


def verify(
    catalogs: Sequence[CatalogInput],
    missions: Sequence[str | Path | MissionScript] = (),
    behaviors: BehaviorSet | None = None,
) -> Report:
    """Verify catalogs (paths or loaded catalogs) and the mission scripts (paths, glob
    patterns or parsed scripts) that use them; every mission is checked against every
    catalog, and with `behaviors` every catalog against that code.

    Every input is read before any rule runs, so unreadable input raises
    (`CatalogError` / `MissionError`, exit code 2 at the CLI) before any output.
    """
    loaded = [c if isinstance(c, Catalog) else read_catalog(c) for c in catalogs]
    patterns = [m for m in missions if not isinstance(m, MissionScript)]
    scripts = [m for m in missions if isinstance(m, MissionScript)]
    scripts += [read_mission(path) for path in expand_mission_paths(patterns)]
    findings: list[Finding] = []
    for catalog in loaded:
        findings.extend(check_catalog(catalog, behaviors=behaviors))
        note = f" [catalog {catalog.source}]" if len(loaded) > 1 else ""
        for script in scripts:
            findings.extend(check_mission(script, catalog, note))
    return Report(
        tuple(findings),
        catalogs=tuple(c.source for c in loaded),
        missions=tuple(s.path for s in scripts),
    )
