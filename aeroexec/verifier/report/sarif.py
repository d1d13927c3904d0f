"""SARIF 2.1.0 (OASIS), as GitHub code scanning accepts it.

One run; the tool's rules are every rule of the registry (so `ruleIndex` is stable),
each with a `helpUri` to its paragraph of docs/rules.md when the docs can be found;
each result has the rule id, a level, the message, one physical location (a region
only when the line is known), a `partialFingerprints` entry that survives line shifts
(rule, file and subjects, not the line), a code flow for mission findings (the path
through the mission), related locations for the helper calls leading to it and, as
properties, the subjects and the witness. Inputs that could not be read are tool
execution notifications of the run's invocation (with their location), and the
invocation is then not successful: the log stays valid and holds the other inputs'
results.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path, PurePosixPath
from typing import Any
from urllib.parse import quote

from aeroexec import __version__
from aeroexec.catalog.model import Severity
from aeroexec.verifier.docs import rule_doc_url
from aeroexec.verifier.findings import Finding, InputError, PathStep, Report
from aeroexec.verifier.registry import Rule, all_rules

#: The key of our own fingerprint in `partialFingerprints` (versioned, as SARIF asks).
FINGERPRINT = "aeroexecFinding/v1"

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
    url = rule_doc_url(rule.code)
    if url is not None:
        entry["helpUri"] = url
    return entry


def _physical(file: str, line: int, column: int, root: Path) -> dict[str, Any]:
    location: dict[str, Any] = {"artifactLocation": artifact_location(file, root)}
    if line > 0:
        region: dict[str, int] = {"startLine": line}
        if column > 0:
            region["startColumn"] = column
        location["region"] = region
    return location


def _fingerprint(finding: Finding, uri: str, occurrence: int) -> str:
    """What identifies a finding across runs: rule, file and subjects (the names it is
    about), not the line, which moves when the file is edited above it."""
    key = "\0".join([finding.rule, uri, *finding.subjects, str(occurrence)])
    return hashlib.sha256(key.encode("utf-8")).hexdigest()[:32]


def _code_flow(file: str, path: tuple[PathStep, ...], root: Path) -> dict[str, Any]:
    locations = [
        {
            "location": {
                "physicalLocation": _physical(file, step.line, step.column, root),
                "message": {"text": step.describe()},
            }
        }
        for step in path
    ]
    return {"threadFlows": [{"locations": locations}]}


def _result(
    finding: Finding, index: dict[str, int], root: Path, seen: dict[tuple[str, ...], int]
) -> dict[str, Any]:
    location = _physical(finding.file, finding.line, finding.column, root)
    uri = location["artifactLocation"]["uri"]
    identity = (finding.rule, uri, *finding.subjects)
    occurrence = seen.get(identity, 0)
    seen[identity] = occurrence + 1
    result: dict[str, Any] = {
        "ruleId": finding.rule,
        "level": _LEVELS[finding.severity],
        "message": {"text": finding.message},
        "locations": [{"physicalLocation": location}],
        "partialFingerprints": {FINGERPRINT: _fingerprint(finding, uri, occurrence)},
        "properties": {
            "subjects": list(finding.subjects),
            "witness": None if finding.witness is None else finding.witness.to_list(),
        },
    }
    if finding.path:
        result["codeFlows"] = [_code_flow(finding.file, finding.path, root)]
    if finding.related:
        result["relatedLocations"] = [
            {
                "id": number,
                "physicalLocation": _physical(note.file, note.line, note.column, root),
                "message": {"text": note.message},
            }
            for number, note in enumerate(finding.related)
        ]
    if finding.rule in index:
        result["ruleIndex"] = index[finding.rule]
    return result


def _notification(error: InputError, root: Path) -> dict[str, Any]:
    notification: dict[str, Any] = {"level": "error", "message": {"text": error.message}}
    if error.file:
        physical = _physical(error.file, error.line, error.column, root)
        notification["locations"] = [{"physicalLocation": physical}]
    return notification


def to_sarif(report: Report, root: Path | None = None) -> dict[str, Any]:
    root = (root or Path.cwd()).resolve()
    rules = all_rules()
    index = {rule.code: i for i, rule in enumerate(rules)}
    seen: dict[tuple[str, ...], int] = {}
    invocation = {
        "executionSuccessful": not report.input_errors,
        "toolExecutionNotifications": [_notification(e, root) for e in report.input_errors],
    }
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
                "invocations": [invocation],
                "originalUriBaseIds": {SRCROOT: {"uri": root.as_uri() + "/"}},
                "columnKind": "unicodeCodePoints",
                "results": [_result(f, index, root, seen) for f in report.findings],
            }
        ],
    }


def render(report: Report) -> str:
    return json.dumps(to_sarif(report), indent=2, ensure_ascii=False) + "\n"
