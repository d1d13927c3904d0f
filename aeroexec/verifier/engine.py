"""Run the verifier: read catalogs and missions, apply every rule, build the report.

Many inputs, one verdict: an input that cannot be read (a missing file, invalid YAML,
a mission that is not Python) is recorded as an `InputError` and the others are still
verified; the report's exit code is then 2.

What only some runs need is imported when they need it (start-up time of `aeroexec
verify CATALOG`): the mission checks (the folder, the executive that runs the calls)
with missions, the task rules with a task catalog, the witness runs with behaviors.
"""

from __future__ import annotations

import glob
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from aeroexec import interrupts
from aeroexec.catalog.formats import AnyCatalog, catalog_from_root, read_any_catalog
from aeroexec.catalog.loader import read_catalog_text
from aeroexec.catalog.model import Catalog
from aeroexec.catalog.tasks import TaskCatalog
from aeroexec.catalog.yamlnodes import YNode, load_yaml
from aeroexec.errors import AeroexecError, CatalogError, Mark
from aeroexec.executive.behavior import Behavior
from aeroexec.gc_pause import paused_gc
from aeroexec.vehicles.world import World
from aeroexec.verifier.findings import Finding, InputError, Report
from aeroexec.verifier.graphs import CatalogGraphs
from aeroexec.verifier.registry import catalog_checks, code_checks, task_checks
from aeroexec.verifier.signals import SignalUse, check_signal_uses

if TYPE_CHECKING:
    from aeroexec.plugins.discovery import BehaviorSet
    from aeroexec.verifier.bt_missions import BtMission
    from aeroexec.verifier.missions import MissionScript
    from aeroexec.verifier.selection import RuleSelection

CatalogInput = str | Path | Catalog | TaskCatalog
Library = Mapping[str, type[Behavior]]


def expand_catalog_paths(patterns: Iterable[str | Path]) -> list[str]:
    """Catalog paths as given; glob patterns that name no existing file (quoted on the
    command line, or on Windows) are expanded here. `CatalogError` for a pattern that
    matches nothing; a plain missing path is left for the loader to report."""
    result: list[str] = []
    for pattern in patterns:
        text = str(pattern)
        if not glob.has_magic(text) or _exists(text):
            result.append(text)
            continue
        matches = sorted(glob.glob(text, recursive=True))
        if not matches:
            raise CatalogError("no catalog matches this pattern", Mark(text))
        result.extend(matches)
    return result


def _exists(path: str) -> bool:
    try:
        return Path(path).exists()
    except OSError:  # e.g. a name too long: the loader says so
        return False


def check_catalog(
    catalog: Catalog,
    codes: Iterable[str] | None = None,
    *,
    world: World | None = None,
    library: Library | None = None,
    behaviors: BehaviorSet | None = None,
) -> list[Finding]:
    """The loader's diagnostics plus every catalog rule's findings (unsorted).

    `codes` restricts the rules that run (loader diagnostics always pass through);
    `world` gives the vehicle limits (default: the built-in world), `library` the
    behavior implementations whose declarations rules read (default: those of
    `behaviors`, else the standard library). With `behaviors` (the implementations the
    project runs), the catalog is checked against them too (AX9xx).
    """
    wanted = None if codes is None else set(codes)
    findings = [Finding.from_diagnostic(d) for d in catalog.diagnostics]
    if library is None and behaviors is not None:
        library = behaviors.library()
    graphs = CatalogGraphs(catalog, world, library)
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
        from aeroexec.verifier.witness_run import realize_findings

        findings = realize_findings(catalog, findings, behaviors.library())
    return findings


def check_task_catalog(catalog: TaskCatalog, codes: Iterable[str] | None = None) -> list[Finding]:
    """The task loader's diagnostics plus every task rule's findings (unsorted)."""
    from aeroexec.verifier.task_rules import TaskContext

    wanted = None if codes is None else set(codes)
    findings = [Finding.from_diagnostic(d) for d in catalog.diagnostics]
    context = TaskContext(catalog)
    for rule in task_checks():
        if wanted is not None and rule.code not in wanted:
            continue
        assert rule.check is not None
        findings.extend(rule.check(context))  # type: ignore[arg-type]
    # `run` cannot run a task catalog: its witnesses are replayed on the model instead.
    from aeroexec.verifier.task_witness import checked_on_model

    return checked_on_model(catalog, findings)


def check_any_catalog(
    catalog: AnyCatalog,
    *,
    world: World | None = None,
    library: Library | None = None,
    behaviors: BehaviorSet | None = None,
) -> list[Finding]:
    if isinstance(catalog, TaskCatalog):
        return check_task_catalog(catalog)
    return check_catalog(catalog, world=world, library=library, behaviors=behaviors)


def verify_catalog(catalog: AnyCatalog) -> Report:
    """Verify one loaded catalog (a behavior catalog or a task catalog)."""
    return Report(tuple(check_any_catalog(catalog)), catalogs=(catalog.source,))


def verify_catalog_file(path: str | Path) -> Report:
    """Read (leniently) and verify one catalog file of any generation; `CatalogError`
    if unreadable."""
    return verify_catalog(read_any_catalog(path))


def _looks_like_bt_mission(root: YNode | None) -> bool:
    # Checked before importing the mission checks (start-up time of a catalog run).
    return (
        root is not None
        and root.is_map
        and root.get("nodes") is not None
        and not any(root.get(k) is not None for k in ("behavior_descriptors", "behaviors", "tasks"))
    )


def _read_catalogs(
    sources: Sequence[CatalogInput], errors: list[InputError], trees: list[BtMission]
) -> list[AnyCatalog]:
    """The catalogs; a behavior-tree mission given among them goes to `trees`."""
    loaded: list[AnyCatalog] = []
    for source in sources:
        if isinstance(source, (Catalog, TaskCatalog)):
            loaded.append(source)
            continue
        try:
            paths = expand_catalog_paths([source])
        except AeroexecError as exc:
            errors.append(InputError.of(exc, str(source)))
            continue
        for path in paths:
            interrupts.check()
            try:
                text, file = read_catalog_text(path)
                root = load_yaml(text, file)
                if _looks_like_bt_mission(root):
                    from aeroexec.verifier.bt_missions import parse_bt_mission

                    trees.append(parse_bt_mission(root, file))
                else:
                    loaded.append(catalog_from_root(root, text, file))
            except AeroexecError as exc:
                errors.append(InputError.of(exc, path))
    return loaded


def _read_missions(
    sources: Sequence[str | Path | MissionScript],
    errors: list[InputError],
    trees: list[BtMission],
) -> list[MissionScript]:
    """Python mission scripts; behavior-tree missions (`.yaml`, `.yml`) go to `trees`."""
    if not sources:
        return []
    from aeroexec.verifier.bt_missions import read_bt_mission
    from aeroexec.verifier.missions import MissionScript, expand_mission_paths, read_mission

    scripts = [m for m in sources if isinstance(m, MissionScript)]
    for pattern in (m for m in sources if not isinstance(m, MissionScript)):
        try:
            paths = expand_mission_paths([pattern])
        except AeroexecError as exc:
            errors.append(InputError.of(exc, str(pattern)))
            continue
        for path in paths:
            interrupts.check()
            try:
                if Path(path).suffix.lower() in (".yaml", ".yml"):
                    trees.append(read_bt_mission(path))
                else:
                    scripts.append(read_mission(path))
            except AeroexecError as exc:
                errors.append(InputError.of(exc, path))
    return scripts


def verify(
    catalogs: Sequence[CatalogInput],
    missions: Sequence[str | Path | MissionScript] = (),
    *,
    world: World | None = None,
    library: Library | None = None,
    behaviors: BehaviorSet | None = None,
    signals: Sequence[SignalUse] = (),
    selection: RuleSelection | None = None,
    in_place: bool = True,
) -> Report:
    """Verify catalogs of any generation (paths, glob patterns or loaded catalogs) and
    the mission scripts (paths, glob patterns or parsed scripts) that use them; every
    mission is checked against every behavior catalog, and with `behaviors` every
    behavior catalog against that code.

    An input that cannot be read becomes an `InputError` of the report (exit code 2)
    and the rest are verified all the same. `world` (the vehicle's limits) and `library`
    (the behavior implementations, for their declared situations and destinations)
    default to the built-in world and the standard library. `signals`: the uses of
    signals in property files (`verify --spec`), checked against every behavior catalog.

    `selection` keeps the rules (and per-file ignores) asked for (default: every
    rule); with `in_place`, a finding whose line carries a suppression comment
    (`# noqa: AX711`, `# aeroexec: ignore[AX401]`) is left out and counted in
    `Report.suppressed`.
    """
    # The rules build graphs and indexes as large as the catalog: no cyclic garbage
    # worth the collector's passes over everything already loaded.
    with paused_gc():
        report = _verify(catalogs, missions, world, library, behaviors, signals)
    return filter_report(report, selection, in_place)


def filter_report(
    report: Report, selection: RuleSelection | None = None, in_place: bool = True
) -> Report:
    """The report less the findings `selection` does not ask for, and (with
    `in_place`) less those a comment on their line suppresses."""
    findings = report.findings
    if selection is not None and not selection.everything:
        findings = tuple(f for f in findings if selection.enabled(f.rule, f.file))
    suppressed = 0
    if in_place and findings:
        from aeroexec.verifier.suppress import Suppressions

        comments = Suppressions()
        kept = tuple(f for f in findings if not comments.suppressed(f.file, f.line, f.rule))
        suppressed = len(findings) - len(kept)
        if suppressed:
            findings = kept
    if len(findings) == len(report.findings):
        return report  # nothing left out: no second sort of every finding
    return Report(
        findings,
        report.catalogs,
        report.missions,
        report.hidden,
        report.input_errors,
        report.suppressed + suppressed,
    )


def _verify(
    catalogs: Sequence[CatalogInput],
    missions: Sequence[str | Path | MissionScript],
    world: World | None,
    library: Library | None,
    behaviors: BehaviorSet | None,
    signals: Sequence[SignalUse] = (),
) -> Report:
    if library is None and behaviors is not None:
        library = behaviors.library()
    errors: list[InputError] = []
    trees: list[BtMission] = []
    loaded = _read_catalogs(catalogs, errors, trees)
    scripts = _read_missions(missions, errors, trees)
    findings: list[Finding] = []
    behavior_catalogs = [c for c in loaded if isinstance(c, Catalog)]
    for catalog in loaded:
        interrupts.check()
        findings.extend(
            check_any_catalog(catalog, world=world, library=library, behaviors=behaviors)
        )
    # Missions use the behavior API (execute/activate/inhibit_behavior): they are
    # checked against the behavior catalogs.
    if scripts:
        from aeroexec.verifier.missions import check_mission
    for index, catalog in enumerate(behavior_catalogs):
        note = f" [catalog {catalog.source}]" if len(behavior_catalogs) > 1 else ""
        for script in scripts:
            findings.extend(check_mission(script, catalog, note, library=library, world=world))
        findings.extend(check_signal_uses(signals, catalog, note, faults=index == 0))
    # Behavior-tree missions: against task catalogs on the coordinator's model, against
    # behavior catalogs as the Python missions are (their flow, run in the executive).
    if trees:
        from aeroexec.verifier.bt_missions import as_folded, check_bt_mission
        from aeroexec.verifier.missions import check_mission

        task_catalogs = [c for c in loaded if isinstance(c, TaskCatalog)]
        for catalog in task_catalogs:
            note = f" [catalog {catalog.source}]" if len(loaded) > 1 else ""
            for tree in trees:
                findings.extend(check_bt_mission(tree, catalog, note))
        folded = [as_folded(tree) for tree in trees]
        for catalog in behavior_catalogs:
            note = f" [catalog {catalog.source}]" if len(loaded) > 1 else ""
            for script in folded:
                findings.extend(check_mission(script, catalog, note, library=library, world=world))
    return Report(
        tuple(findings),
        catalogs=tuple(c.source for c in loaded),
        missions=(*(s.path for s in scripts), *(t.path for t in trees)),
        input_errors=tuple(errors),
    )
