"""SARIF 2.1.0 (OASIS), as GitHub code scanning accepts it.

One run; the tool's rules are every rule of the registry (so `ruleIndex` is stable);
each result has the rule id, a level, the message, one physical location (a region
only when the line is known) and, as properties, the subjects and the witness.
"""

from __future__ import annotations

import json
from pathlib import Path, PurePosixPath
from typing import Any
from urllib.parse import quote

from aeroexec import __version__
from aeroexec.catalog.model import Severity
from aeroexec.verifier.findings import Finding, Report
from aeroexec.verifier.registry import Rule, all_rules

SCHEMA_URI = "https://json.schemastore.org/sarif-2.1.0.json"
_LEVELS = {Severity.ERROR: "error", Severity.WARNING: "warning", Severity.INFO: "note"}


SRCROOT = "%SRCROOT%"


def artifact_location(file: str, root: Path) -> dict[str, str]:
    """A relative URI reference against %SRCROOT% (the working directory) for files
    under it — what code scanning resolves against the repository root — else an
    absolute file:// URI."""
    path = Path(file)
    if path.is_absolute():
        try:
            path = path.relative_to(root)
        except ValueError:
            return {"uri": path.as_uri()}
    uri = quote(PurePosixPath(*path.parts).as_posix(), safe="/")
    return {"uri": uri, "uriBaseId": SRCROOT}


def _rule(rule: Rule) -> dict[str, Any]:
    entry: dict[str, Any] = {
        "id": rule.code,
        "name": rule.name,
        "shortDescription": {"text": f"{rule.name} ({rule.area.lower()})"},
        "fullDescription": {"text": rule.doc},
        "help": {"text": rule.doc},
        "properties": {"kind": rule.kind, "witness": rule.witness},
    }
    if rule.severity is not None:
        entry["defaultConfiguration"] = {"level": _LEVELS[rule.severity]}
    return entry


def _result(finding: Finding, index: dict[str, int], root: Path) -> dict[str, Any]:
    location: dict[str, Any] = {"artifactLocation": artifact_location(finding.file, root)}
    if finding.line > 0:
        region: dict[str, int] = {"startLine": finding.line}
        if finding.column > 0:
            region["startColumn"] = finding.column
        location["region"] = region
    result: dict[str, Any] = {
        "ruleId": finding.rule,
        "level": _LEVELS[finding.severity],
        "message": {"text": finding.message},
        "locations": [{"physicalLocation": location}],
        "properties": {
            "subjects": list(finding.subjects),
            "witness": None if finding.witness is None else finding.witness.to_list(),
        },
    }
    if finding.rule in index:
        result["ruleIndex"] = index[finding.rule]
    return result


def to_sarif(report: Report, root: Path | None = None) -> dict[str, Any]:
    root = (root or Path.cwd()).resolve()
    rules = all_rules()
    index = {rule.code: i for i, rule in enumerate(rules)}
    return {
        "$schema": SCHEMA_URI,
        "version": "2.1.0",
        "runs": [
            {
                "tool": {
                    "driver": {
                        "name": "aeroexec",
                        "semanticVersion": __version__,
                        "rules": [_rule(rule) for rule in rules],
                    }
                },
                "originalUriBaseIds": {SRCROOT: {"uri": root.as_uri() + "/"}},
                "columnKind": "unicodeCodePoints",
                "results": [_result(f, index, root) for f in report.findings],
            }
        ],
    }


def render(report: Report) -> str:
    return json.dumps(to_sarif(report), indent=2, ensure_ascii=False) + "\n"
