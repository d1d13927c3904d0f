"""Compiler-style text: `file:line:col: severity CODE message`, then a summary line."""

from __future__ import annotations

import typer

from aeroexec.catalog.model import Severity
from aeroexec.verifier.findings import Finding, Report

_COLORS = {Severity.ERROR: "red", Severity.WARNING: "yellow", Severity.INFO: "cyan"}


def _plural(count: int, word: str) -> str:
    return f"{count} {word}{'' if count == 1 else 's'}"


def format_finding(finding: Finding, *, color: bool = False) -> str:
    severity = finding.severity.value
    location = finding.location
    if color:
        severity = typer.style(severity, fg=_COLORS[finding.severity], bold=True)
        location = typer.style(location, bold=True)
    return f"{location}: {severity} {finding.rule} {finding.message}"


def summary_line(report: Report, hidden: int = 0) -> str:
    inputs = len(report.catalogs) + len(report.missions)
    counts = [
        _plural(report.errors, "error"),
        _plural(report.warnings, "warning"),
        _plural(report.infos, "info"),
    ]
    line = f"{', '.join(counts)} in {_plural(inputs, 'file')}"
    if hidden:
        line += f" ({_plural(hidden, 'finding')} below --min-severity not shown)"
    if report.suppressed:
        line += f" ({report.suppressed} suppressed in place)"
    if report.input_errors:
        unread = len(report.input_errors)
        line += f"; {_plural(unread, 'input')} could not be read"
    return line


def render(report: Report, *, witness: bool = False, color: bool = False) -> str:
    """Findings and a summary; nothing when no input could be read (the unreadable
    ones are reported on stderr, one line each)."""
    if report.input_errors and not (report.catalogs or report.missions):
        return ""
    lines: list[str] = []
    omitted = report.omitted_by_rule()
    last = {f.rule: i for i, f in enumerate(report.findings) if f.rule in omitted}
    for index, finding in enumerate(report.findings):
        lines.append(format_finding(finding, color=color))
        lines += [f"{note.location}: note: {note.message}" for note in finding.related]
        if witness and finding.witness is not None:
            lines.append(f"    witness: {finding.witness.describe()}")
        if last.get(finding.rule) == index:
            lines.append(more_line(finding.rule, omitted[finding.rule]))
    lines += [more_line(rule, count) for rule, count in omitted.items() if rule not in last]
    lines.append(summary_line(report, report.hidden))
    return "\n".join(lines) + "\n"


def more_line(rule: str, count: int) -> str:
    """What stands for the findings of `rule` beyond --max-findings."""
    return (
        f"  … and {count:,} more {rule} {'finding' if count == 1 else 'findings'} "
        "(--max-findings; -f json or sarif lists them all)"
    )
