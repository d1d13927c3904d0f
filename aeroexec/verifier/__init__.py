"""The offline verifier: rules over a catalog's graphs, mission checks, witnesses, reports.

    from aeroexec.verifier import verify
    report = verify(["catalog/default.yaml"], missions=["missions/*.py"])
    for finding in report.findings:
        print(finding)              # file:line:col: severity CODE message
    report.exit_code(strict=False)  # 0 no errors, 1 errors

Rules are registered in `aeroexec.verifier.registry` (`all_rules()`, `get(code)`); each has a
code, a severity and a one-paragraph doc. `docs/rules.md` is generated from it
(`python -m aeroexec.verifier.docs`).
"""

from aeroexec.verifier.engine import (
    check_catalog,
    expand_catalog_paths,
    verify,
    verify_catalog,
    verify_catalog_file,
)
from aeroexec.verifier.findings import Finding, Outcome, Report, Step, Witness
from aeroexec.verifier.graphs import CatalogGraphs
from aeroexec.verifier.missions import MissionScript, check_mission, parse_mission, read_mission
from aeroexec.verifier.registry import Rule, all_rules, get

__all__ = [
    "CatalogGraphs",
    "Finding",
    "MissionScript",
    "Outcome",
    "Report",
    "Rule",
    "Step",
    "Witness",
    "all_rules",
    "check_catalog",
    "check_mission",
    "expand_catalog_paths",
    "get",
    "parse_mission",
    "read_mission",
    "verify",
    "verify_catalog",
    "verify_catalog_file",
]
