"""Explore's outputs: text (the table, the causes, the commands that reproduce), json,
junit (a test case per injection) and github (annotations of the violated properties, by
`aeroexec check`'s own reporter on the kept recordings).

The table has a row per transition (plus offset) and a column per fault kind; a cell is
`held`, `failed` (the mission failed cleanly: no property violated) or `VIOLATED`.
Nothing in the text or json depends on timing or on where the runs ran.
"""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from typing import Any

from aeroexec.properties.check import CheckReport, check_recording
from aeroexec.properties.report import github as github_annotations
from aeroexec.properties.spec import load_properties
from aeroexec.recording.transitions import NS_PER_S
from aeroexec.whatif.explore import ERROR, OUTCOMES, VIOLATED, ExploreResult, RunResult
from aeroexec.whatif.plan import Probe

#: Injections named per cause in the text (json lists them all).
SHOWN = 4
CELL = {"held": "held", "failed": "failed", "violated": "VIOLATED", "error": "error"}


def _rows(result: ExploreResult, recording: str) -> list[tuple[Probe, list[Probe]]]:
    """(first probe of the row, its probes by kind) in table order."""
    rows: dict[tuple[str, int], list[Probe]] = {}
    for probe in result.plan.probes:
        if probe.recording == recording:
            rows.setdefault((probe.transition.label, probe.offset_ns), []).append(probe)
    return [(probes[0], probes) for probes in rows.values()]


def _summary(result: ExploreResult) -> str:
    counts = result.counts()
    total = len(result.plan.probes)
    parts = [f"{counts[o]} {o}" for o in OUTCOMES if counts[o] or o != "error"]
    return f"{total} injection(s) in {len(result.results)} run(s): " + ", ".join(parts)


def text(result: ExploreResult) -> str:
    lines: list[str] = []
    kinds = list(result.options.kinds)
    for recording in result.plan.transitions:
        rows = _rows(result, recording)
        flight = result.flights.get(recording)
        twin = f" (the simulated twin of the flight {flight})" if flight else ""
        lines.append(f"{recording}{twin}: {len(rows)} moment(s) x {len(kinds)} fault(s)")
        width = max([len("transition"), *(len(first.row) for first, _ in rows)])
        widths = [max(len(k), len("VIOLATED")) for k in kinds]
        header = f"  {'transition':<{width}}  {'at s':>7}  " + "  ".join(
            f"{k:<{w}}" for k, w in zip(kinds, widths, strict=True)
        )
        lines.append(header.rstrip())
        for first, probes in rows:
            by_kind = {p.fault: result.outcome(p) for p in probes}
            at = (first.transition.time_ns + first.offset_ns) / NS_PER_S
            cells = "  ".join(
                f"{CELL[by_kind[k]]:<{w}}" for k, w in zip(kinds, widths, strict=True)
            )
            lines.append(f"  {first.row:<{width}}  {at:>7.2f}  {cells}".rstrip())
    groups = result.groups()
    if groups:
        lines.append("violations by cause (property at transition kind and behavior):")
        for group in groups:
            names = ", ".join(f"{p.fault}@{p.row}" for p in group.probes[:SHOWN])
            more = len(group.probes) - SHOWN
            lines.append(
                f"  {group.property} at {group.kind} {group.behavior}: "
                f"{len(group.probes)} injection(s): {names}"
                + (f" and {more} more" if more > 0 else "")
            )
        lines.append("reproduce (each exits 1; `aeroexec check FILE` exits 1 on the file):")
        for run in result.results:
            if run.outcome == VIOLATED:
                lines.append(f"  {run.reproduce}")
    for run in result.errors:
        lines.append(f"error: {run.run.fault}@{run.run.when}: {run.error}")
    late = sum(1 for p in result.plan.probes if result.result(p).notes)
    if late:
        lines.append(
            f"note: {late} injection(s) were due after the session had ended (never struck)"
        )
    lines.append(_summary(result))
    return "\n".join(lines) + "\n"


def _run_json(index: int, run: RunResult) -> dict[str, Any]:
    out: dict[str, Any] = {
        "run": index,
        "recording": run.run.recording,
        "fault": run.run.fault,
        "when": run.run.when,
        "at_s": run.run.due_ns / NS_PER_S,
        "outcome": run.outcome,
        "violated": list(run.violated),
        "failures": list(run.failures),
    }
    if run.notes:
        out["notes"] = list(run.notes)
    if run.error is not None:
        out["error"] = run.error
    if run.kept is not None:
        out["mcap"] = run.kept
        out["reproduce"] = run.reproduce
    return out


def as_json(result: ExploreResult) -> str:
    table = [
        {
            "recording": p.recording,
            "transition": p.transition.label,
            "kind": p.transition.kind,
            "behavior": p.transition.behavior,
            "time_s": p.transition.time_ns / NS_PER_S,
            "offset_s": p.offset_ns / NS_PER_S,
            "fault": p.fault,
            "outcome": result.outcome(p),
            "run": p.run,
        }
        for p in result.plan.probes
    ]
    body = {
        "violated": result.violated,
        "counts": result.counts(),
        "faults": list(result.options.kinds),
        "injections": table,
        "runs": [_run_json(i, r) for i, r in enumerate(result.results)],
        "groups": [
            {
                "property": g.property,
                "kind": g.kind,
                "behavior": g.behavior,
                "injections": [f"{p.fault}@{p.row}" for p in g.probes],
            }
            for g in result.groups()
        ],
        "twins": [{"flight": f, "twin": t} for t, f in result.flights.items()],
        "summary": _summary(result),
    }
    return json.dumps(body, indent=2) + "\n"


def junit(result: ExploreResult) -> str:
    """A test suite per recording, a test case per injection: a violated property is a
    failure, a run that could not be made an error, a clean mission failure passes (its
    failures in system-out)."""
    root = ET.Element("testsuites", name="aeroexec explore")
    for recording in result.plan.transitions:
        probes = [p for p in result.plan.probes if p.recording == recording]
        outcomes = [result.outcome(p) for p in probes]
        suite = ET.SubElement(
            root,
            "testsuite",
            name=recording,
            tests=str(len(probes)),
            failures=str(outcomes.count(VIOLATED)),
            errors=str(outcomes.count(ERROR)),
            skipped="0",
        )
        for probe, outcome in zip(probes, outcomes, strict=True):
            run = result.result(probe)
            case = ET.SubElement(
                suite, "testcase", classname=recording, name=f"{probe.fault}@{probe.row}"
            )
            if outcome == VIOLATED:
                failure = ET.SubElement(
                    case, "failure", message="violated: " + ", ".join(run.violated)
                )
                failure.text = f"{run.reproduce}\n" + "\n".join(run.failures)
            elif outcome == ERROR:
                ET.SubElement(case, "error", message=run.error or "")
            elif run.failures:
                ET.SubElement(case, "system-out").text = "\n".join(run.failures)
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, "unicode") + "\n"


def violation_reports(result: ExploreResult, spec: Sequence[str]) -> list[CheckReport]:
    """`aeroexec check`'s reports of the kept runs, named after their injection."""
    properties = load_properties(list(spec))
    reports = []
    for run in result.results:
        if run.outcome == VIOLATED and run.kept is not None:
            report = check_recording(run.kept, properties)
            name = f"{run.run.recording} ({run.run.fault}@{run.run.when})"
            reports.append(CheckReport(name, report.verdicts, report.duration_s))
    return reports


def github(result: ExploreResult) -> str:
    """One workflow annotation per violation, on the line that defines the property."""
    return github_annotations(violation_reports(result, result.options.spec))
