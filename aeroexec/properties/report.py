"""`aeroexec check`'s outputs: text, json, sarif, junit and github.

The escaping rules of GitHub's workflow commands and the JUnit layout are the ones the
verifier's and replay's reporters use; they are restated here (a few lines) because the
tools do not import each other (docs/design.md#layers).
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

from aeroexec import __version__
from aeroexec.properties.check import MISSING, VIOLATED, CheckReport, Verdict
from aeroexec.properties.signals import FAMILIES, SIGNALS
from aeroexec.properties.spec import Parameter, Property

_LEVEL = {"error": "error", "warning": "warning", "note": "note"}
_GITHUB = {"error": "error", "warning": "warning", "note": "notice"}


def _t(verdict: Verdict) -> str:
    start = verdict.interval_s[0] if verdict.interval_s else 0.0
    return f"t={start:.2f}s"


# text, JSON and JUnit render a recording's verdicts from their JSON form (`recording_json`):
# a replay's worker (a process, a Ray node) sends that form back, a shard's report carries
# it, and `report merge` renders it the same way (aeroexec.replay: the same bytes).
def recording_json(report: CheckReport) -> dict[str, Any]:
    """One recording's verdicts as plain data (JSON values, picklable)."""
    return {
        "recording": report.recording,
        "duration_s": report.duration_s,
        "verdicts": [verdict_json(v) for v in report.verdicts],
    }


def failed(entries: Sequence[dict[str, Any]]) -> bool:
    """Whether a property of severity error was violated (`CheckReport.failed`)."""
    return any(
        v["status"] == VIOLATED and v["severity"] == "error"
        for entry in entries
        for v in entry["verdicts"]
    )


def _start(verdict: dict[str, Any]) -> str:
    interval = verdict.get("interval")
    return f"t={(interval['start_s'] if interval else 0.0):.2f}s"


def text(reports: Sequence[CheckReport], *, verbose: bool = False) -> str:
    """`REC: t=12.40s: error PROPERTY: message (spec.yaml:LINE)`, one line per violation
    (and per property not checked), then a summary."""
    return text_of([recording_json(r) for r in reports], verbose=verbose)


def text_of(entries: Sequence[dict[str, Any]], *, verbose: bool = False) -> str:
    """`text` of recordings' verdicts in their JSON form."""
    lines = []
    for entry in entries:
        recording = entry["recording"]
        for verdict in entry["verdicts"]:
            name, where, message = verdict["property"], verdict["defined_at"], verdict["message"]
            if verdict["status"] == VIOLATED:
                lines.append(
                    f"{recording}: {_start(verdict)}: {verdict['severity']} {name}: "
                    f"{message} ({where})"
                )
            elif verdict["status"] == MISSING:
                lines.append(f"{recording}: note {name}: {message} ({where})")
            elif verbose:
                lines.append(f"{recording}: ok {name}: {message}")
    all_verdicts = [v for entry in entries for v in entry["verdicts"]]
    violated = sum(1 for v in all_verdicts if v["status"] == VIOLATED)
    checked = sum(1 for v in all_verdicts if v["status"] != MISSING)
    lines.append(
        f"{len(entries)} recording(s), {checked} check(s): "
        + (f"{violated} violated" if violated else "all properties hold")
    )
    return "\n".join(lines) + "\n"


def _number(value: float | None) -> float | None:
    return None if value is None or not math.isfinite(value) else value + 0.0


def verdict_json(verdict: Verdict) -> dict[str, Any]:
    prop = verdict.property
    out: dict[str, Any] = {
        "property": prop.name,
        "status": verdict.status,
        "severity": prop.severity,
        "robustness": _number(verdict.robustness),
        "defined_at": prop.where,
        "formula": prop.formula.text,
        "message": verdict.message(),
    }
    if verdict.interval_s is not None:
        out["interval"] = {"start_s": verdict.interval_s[0], "end_s": verdict.interval_s[1]}
    if verdict.missing:
        out["missing"] = [{"signal": n, "why": why} for n, why in verdict.missing]
    if prop.action:
        out["action"] = prop.action
    return out


def as_json(reports: Sequence[CheckReport]) -> str:
    return json.dumps(json_of([recording_json(r) for r in reports]), indent=2) + "\n"


def json_of(entries: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The JSON report of recordings' verdicts in their JSON form."""
    violated = sum(1 for e in entries for v in e["verdicts"] if v["status"] == VIOLATED)
    return {"recordings": list(entries), "violated": violated}


def _escape(value: str) -> str:
    return value.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")


def _escape_property(value: str) -> str:
    return _escape(value).replace(":", "%3A").replace(",", "%2C")


def github(reports: Sequence[CheckReport]) -> str:
    """One workflow annotation per violation, on the line that defines the property."""
    lines = []
    for report in reports:
        for verdict in report.violated:
            prop = verdict.property
            props = [f"file={_escape_property(prop.mark.file)}"]
            if prop.mark.line:
                props.append(f"line={prop.mark.line}")
            props.append(f"title={_escape_property(prop.name)}")
            message = f"{report.recording}: {_t(verdict)}: {verdict.message()}"
            lines.append(f"::{_GITHUB[prop.severity]} {','.join(props)}::{_escape(message)}")
    return "".join(line + "\n" for line in lines)


def sarif(reports: Sequence[CheckReport]) -> str:
    rules: dict[str, Property] = {}
    for report in reports:
        for verdict in report.verdicts:
            rules.setdefault(verdict.property.name, verdict.property)
    results = []
    for report in reports:
        for verdict in report.violated:
            prop = verdict.property
            location: dict[str, Any] = {
                "physicalLocation": {
                    "artifactLocation": {"uri": Path(prop.mark.file).as_posix()},
                    **({"region": {"startLine": prop.mark.line}} if prop.mark.line else {}),
                },
                "logicalLocations": [
                    {"name": f"{report.recording}@{_t(verdict)}", "kind": "recording"}
                ],
            }
            results.append(
                {
                    "ruleId": prop.name,
                    "level": _LEVEL[prop.severity],
                    "message": {"text": f"{report.recording}: {_t(verdict)}: {verdict.message()}"},
                    "locations": [location],
                    "properties": verdict_json(verdict),
                }
            )
    log = {
        "$schema": "https://json.schemastore.org/sarif-2.1.0.json",
        "version": "2.1.0",
        "runs": [
            {
                "tool": {
                    "driver": {
                        "name": "aeroexec check",
                        "version": __version__,
                        "rules": [
                            {
                                "id": p.name,
                                "shortDescription": {"text": p.description or p.formula.text},
                                "fullDescription": {"text": p.formula.text},
                                "defaultConfiguration": {"level": _LEVEL[p.severity]},
                            }
                            for p in rules.values()
                        ],
                    }
                },
                "results": results,
            }
        ],
    }
    return json.dumps(log, indent=2) + "\n"


def junit(reports: Sequence[CheckReport], timestamp: str | None = None) -> str:
    """One test suite per recording, one test case per property: a violation is a
    failure, a property whose signals the recording lacks is skipped."""
    return junit_of([recording_json(r) for r in reports], timestamp)


def junit_of(entries: Sequence[dict[str, Any]], timestamp: str | None = None) -> str:
    """`junit` of recordings' verdicts in their JSON form."""
    suites = ET.Element("testsuites", name="aeroexec check")
    for entry in entries:
        recording, verdicts = entry["recording"], entry["verdicts"]
        suite = ET.SubElement(
            suites,
            "testsuite",
            name=recording,
            tests=str(len(verdicts)),
            failures=str(sum(1 for v in verdicts if v["status"] == VIOLATED)),
            skipped=str(sum(1 for v in verdicts if v["status"] == MISSING)),
        )
        if timestamp:
            suite.set("timestamp", timestamp)
        for verdict in verdicts:
            case = ET.SubElement(suite, "testcase", classname=recording, name=verdict["property"])
            if verdict["status"] == VIOLATED:
                failure = ET.SubElement(
                    case, "failure", message=f"{_start(verdict)}: {verdict['message']}"
                )
                failure.text = f"{verdict['formula']}\n({verdict['defined_at']})"
            elif verdict["status"] == MISSING:
                ET.SubElement(case, "skipped", message=verdict["message"])
    ET.indent(suites)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(suites, "unicode") + "\n"


def explain(prop: Property, parameters: Iterable[Parameter] = ()) -> str:
    """What `--explain PROPERTY` prints: the property, the signals it reads and the
    parameters (of `parameters`, the set's) it reads."""
    lines = [
        f"{prop.name} ({prop.where})",
        f"  formula:  {prop.formula.text}",
        f"  severity: {prop.severity}",
    ]
    if prop.description:
        lines.append(f"  meaning:  {prop.description}")
    if prop.action:
        lines.append(f"  action:   {prop.action} (run/fly --spec end the flight so)")
    horizon = prop.formula.horizon_s()
    if horizon is not None:
        lines.append(f"  a violation is final {horizon:g} s after it starts (online)")
    lines.append("  signals:")
    for name in prop.formula.signals:
        lines.append(f"    {name}: {describe_signal(name)}")
    given = {p.name: p for p in parameters}
    if prop.formula.parameters:
        lines.append("  parameters:")
        for name in prop.formula.parameters:
            if name in given:
                lines.append(f"    {name} = {given[name].text} ({given[name].where})")
    return "\n".join(lines) + "\n"


def describe_signal(name: str) -> str:
    for doc in SIGNALS:
        if doc.name == name:
            return f"{doc.meaning} [{doc.unit}] from {doc.source}"
    for prefix, (unit, meaning, source) in FAMILIES.items():
        if name.startswith(prefix):
            return f"{meaning.replace(' B ', ' ').replace(' C ', ' ')} [{unit}] from {source}"
    return "unknown"
