"""The offline verifier: rules over a catalog's graphs, mission checks, witnesses, reports.

    from aeroexec.verifier import verify
    report = verify(["catalog/default.yaml"], missions=["missions/*.py"])
    for finding in report.findings:
        print(finding)              # file:line:col: severity CODE message
    report.input_errors             # inputs that could not be read (the rest was verified)
    report.exit_code(strict=False)  # 0 no errors, 1 errors, 2 an input unreadable

Behavior catalogs (2017 thesis, Aerostack 2.x) and task catalogs (Aerostack 4.x,
2020-2021) are both read (`aeroexec.catalog.formats`); missions are checked call by call
and run as sequences in the executive (`missions`, `mission_fold`, `mission_run`).

Rules are registered in `aeroexec.verifier.registry` (`all_rules()`, `get(code)`); each has a
code, a severity and a one-paragraph doc. `docs/rules.md` is generated from it
(`python -m aeroexec.verifier.docs`).

The names are loaded when first used (PEP 562): `aeroexec verify CATALOG` does not import
the mission checks, and the executive they run, that only missions need."""

from __future__ import annotations

from typing import TYPE_CHECKING

from aeroexec.lazy import lazy_exports

if TYPE_CHECKING:
    from aeroexec.verifier.engine import (
        check_any_catalog,
        check_catalog,
        check_task_catalog,
        expand_catalog_paths,
        verify,
        verify_catalog,
        verify_catalog_file,
    )
    from aeroexec.verifier.findings import (
        Finding,
        InputError,
        Outcome,
        PathStep,
        Report,
        Step,
        Witness,
    )
    from aeroexec.verifier.graphs import CatalogGraphs
    from aeroexec.verifier.missions import MissionScript, check_mission, parse_mission, read_mission
    from aeroexec.verifier.registry import Rule, all_rules, get

__all__ = [
    "CatalogGraphs",
    "Finding",
    "InputError",
    "MissionScript",
    "Outcome",
    "PathStep",
    "Report",
    "Rule",
    "Step",
    "Witness",
    "all_rules",
    "check_any_catalog",
    "check_catalog",
    "check_mission",
    "check_task_catalog",
    "expand_catalog_paths",
    "get",
    "parse_mission",
    "read_mission",
    "verify",
    "verify_catalog",
    "verify_catalog_file",
]

#: Each public name -> the module defining it, imported when the name is first used.
_WHERE = {
    "CatalogGraphs": "graphs",
    "Finding": "findings",
    "InputError": "findings",
    "MissionScript": "missions",
    "Outcome": "findings",
    "PathStep": "findings",
    "Report": "findings",
    "Rule": "registry",
    "Step": "findings",
    "Witness": "findings",
    "all_rules": "registry",
    "check_any_catalog": "engine",
    "check_catalog": "engine",
    "check_mission": "missions",
    "check_task_catalog": "engine",
    "expand_catalog_paths": "engine",
    "get": "registry",
    "parse_mission": "missions",
    "read_mission": "missions",
    "verify": "engine",
    "verify_catalog": "engine",
    "verify_catalog_file": "engine",
}


__getattr__, __dir__ = lazy_exports(__name__, _WHERE, globals())
