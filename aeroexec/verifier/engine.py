"""Run the verifier: read catalogs and missions, apply every rule, build the report.

Many inputs, one verdict: an input that cannot be read (a missing file, invalid YAML,
a mission that is not Python) is recorded as an `InputError` and the others are still
verified; the report's exit code is then 2.

What only some runs need is imported when they need it (start-up time of `aeroexec
verify CATALOG`): the mission checks (the folder, the executive that runs the calls)
with missions, the task rules with a task catalog, the witness runs with behaviors.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
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
from aeroexec.inputs import glob_files, has_magic
from aeroexec.vehicles.world import World
from aeroexec.verifier.findings import Finding, FindingCollector, InputError, Report
from aeroexec.verifier.graphs import CatalogGraphs
from aeroexec.verifier.registry import catalog_checks, code_checks, task_checks
from aeroexec.verifier.signals import SignalUse, check_signal_uses

if TYPE_CHECKING:
    from aeroexec.plugins.discovery import BehaviorSet
    from aeroexec.verifier.bt_missions import BtMission
    from aeroexec.verifier.missions import MissionScript
    from aeroexec.verifier.selection import RuleSelection
    from aeroexec.verifier.suppress import Suppressions

CatalogInput = str | Path | Catalog | TaskCatalog
#: The code of an unused suppression comment (`aeroexec.verifier.suppress.UNUSED`).
UNUSED_SUPPRESSION = "AX001"
Library = Mapping[str, type[Behavior]]


def expand_catalog_paths(patterns: Iterable[str | Path]) -> tuple[list[str], list[CatalogError]]:
    """Catalog paths as given; glob patterns that name no existing file (quoted on the
    command line, or on Windows) are expanded here (`**` recursive). Beside the paths,
    the errors met: a pattern that matches nothing, a directory the search could not
    read (it would otherwise look like "no match", or drop catalogs from the check in
    silence), a match that is a symlink loop. A plain missing path is left for the
    loader to report."""
    result: list[str] = []
    errors: list[CatalogError] = []
    for pattern in patterns:
        text = str(pattern)
        if not has_magic(text) or _exists(text):
            result.append(text)
            continue
        found = glob_files(text)
        errors.extend(CatalogError(u.problem, Mark(u.path)) for u in found.unreadable)
        if not found.files and not found.unreadable:
            errors.append(CatalogError("no catalog matches this pattern", Mark(text)))
        result.extend(found.files)
    return result, errors


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
    return list(
        iter_catalog_findings(catalog, codes, world=world, library=library, behaviors=behaviors)
    )


def iter_catalog_findings(
    catalog: Catalog,
    codes: Iterable[str] | None = None,
    *,
    world: World | None = None,
    library: Library | None = None,
    behaviors: BehaviorSet | None = None,
) -> Iterator[Finding]:
    """`check_catalog`, one finding at a time: a caller that keeps only some of them
    (`FindingCollector`) never holds them all."""
    wanted = None if codes is None else set(codes)
    if library is None and behaviors is not None:
        library = behaviors.library()
    realized: Callable[[Finding], Finding] | None = None
    if behaviors is not None:
        # Witnesses as the real behaviors make them happen (TAKE_OFF first, ...).
        from aeroexec.verifier.witness_run import realize_findings

        code_library = behaviors.library()

        def realize_one(found: Finding) -> Finding:
            return realize_findings(catalog, [found], code_library)[0]

        realized = realize_one

    findings: Iterator[Finding] = (Finding.from_diagnostic(d) for d in catalog.diagnostics)
    graphs = CatalogGraphs(catalog, world, library)
    rules = [r for r in catalog_checks() if wanted is None or r.code in wanted]
    findings = itertools.chain(
        findings,
        *(rule.check(graphs) for rule in rules),  # type: ignore[call-arg]  (catalog rules)
    )
    if behaviors is not None:
        code_rules = [r for r in code_checks() if wanted is None or r.code in wanted]
        findings = itertools.chain(
            findings,
            *(rule.check(graphs, behaviors) for rule in code_rules),  # type: ignore[call-arg]
        )
    for finding in findings:
        yield finding if realized is None else realized(finding)


def check_task_catalog(catalog: TaskCatalog, codes: Iterable[str] | None = None) -> list[Finding]:
    """The task loader's diagnostics plus every task rule's findings (unsorted)."""
    return list(iter_task_findings(catalog, codes))


def iter_task_findings(
    catalog: TaskCatalog, codes: Iterable[str] | None = None
) -> Iterator[Finding]:
    from aeroexec.verifier.task_rules import TaskContext

    wanted = None if codes is None else set(codes)
    yield from (Finding.from_diagnostic(d) for d in catalog.diagnostics)
    context = TaskContext(catalog)
    rules = [r for r in task_checks() if wanted is None or r.code in wanted]
    found = itertools.chain.from_iterable(r.check(context) for r in rules)  # type: ignore[misc, arg-type]
    # `run` cannot run a task catalog: its witnesses are replayed on the model instead.
    from aeroexec.verifier.task_witness import checked_on_model

    yield from checked_on_model(catalog, found)


def check_any_catalog(
    catalog: AnyCatalog,
    *,
    world: World | None = None,
    library: Library | None = None,
    behaviors: BehaviorSet | None = None,
) -> list[Finding]:
    return list(iter_any_findings(catalog, world=world, library=library, behaviors=behaviors))


def iter_any_findings(
    catalog: AnyCatalog,
    *,
    world: World | None = None,
    library: Library | None = None,
    behaviors: BehaviorSet | None = None,
) -> Iterator[Finding]:
    if isinstance(catalog, TaskCatalog):
        return iter_task_findings(catalog)
    return iter_catalog_findings(catalog, world=world, library=library, behaviors=behaviors)


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
        paths, unreadable = expand_catalog_paths([source])
        errors.extend(InputError.of(exc) for exc in unreadable)
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
        paths, unreadable = expand_mission_paths([pattern])
        errors.extend(InputError.of(exc) for exc in unreadable)
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
    max_findings: int | None = None,
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

    With `max_findings`, the report keeps the first that many findings of each rule (by
    place) and counts the rest (`Report.omitted`): memory stays bounded however many a
    catalog has. Selection and suppression come first: what is left out there is
    neither kept nor counted as omitted.
    """
    # The rules build graphs and indexes as large as the catalog: no cyclic garbage
    # worth the collector's passes over everything already loaded.
    with paused_gc():
        admitted = Admission(selection, in_place)
        return _verify(
            catalogs, missions, world, library, behaviors, signals, max_findings, admitted
        )


class Admission:
    """Which findings a report takes: those `selection` asks for (every rule without
    one), less (with `in_place`) those a comment on their line suppresses, counted."""

    def __init__(self, selection: RuleSelection | None, in_place: bool) -> None:
        self.selection = None if selection is None or selection.everything else selection
        self.comments: Suppressions | None = None
        if in_place:
            from aeroexec.verifier.suppress import Suppressions

            self.comments = Suppressions()
        self.suppressed = 0

    def __call__(self, finding: Finding) -> bool:
        if self.selection is not None and not self.selection.enabled(finding.rule, finding.file):
            return False
        if (
            self.comments is not None
            and finding.rule != UNUSED_SUPPRESSION  # decided by the comments themselves
            and self.comments.suppressed(finding.file, finding.line, finding.rule)
        ):
            self.suppressed += 1
            return False
        return True


def _verify(
    catalogs: Sequence[CatalogInput],
    missions: Sequence[str | Path | MissionScript],
    world: World | None,
    library: Library | None,
    behaviors: BehaviorSet | None,
    signals: Sequence[SignalUse] = (),
    max_findings: int | None = None,
    admitted: Admission | None = None,
) -> Report:
    if library is None and behaviors is not None:
        library = behaviors.library()
    errors: list[InputError] = []
    trees: list[BtMission] = []
    loaded = _read_catalogs(catalogs, errors, trees)
    scripts = _read_missions(missions, errors, trees)
    findings = FindingCollector(max_findings, admitted)
    behavior_catalogs = [c for c in loaded if isinstance(c, Catalog)]
    for catalog in loaded:
        interrupts.check()
        findings.extend(
            iter_any_findings(catalog, world=world, library=library, behaviors=behaviors)
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
    if admitted is not None and admitted.comments is not None:
        # Last: a comment is unused only once every finding has had its chance.
        read = (*(c.source for c in loaded), *(s.path for s in scripts), *(t.path for t in trees))
        findings.extend(admitted.comments.unused(read))
    return Report(
        findings.findings(),
        catalogs=tuple(c.source for c in loaded),
        missions=(*(s.path for s in scripts), *(t.path for t in trees)),
        input_errors=tuple(errors),
        omitted=findings.omitted(),
        suppressed=admitted.suppressed if admitted is not None else 0,
    )
