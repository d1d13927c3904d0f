"""GitHub Actions workflow commands: `::error file=F,line=L,col=C,title=CODE::message`.

Escaping follows the runner's rules: in the message `%`, CR and LF are %-encoded; in
property values `:` and `,` are too.
"""

from __future__ import annotations

from aeroexec.catalog.model import Severity
from aeroexec.verifier.findings import Finding, InputError, Report
from aeroexec.verifier.report.text import more_line

_COMMANDS = {Severity.ERROR: "error", Severity.WARNING: "warning", Severity.INFO: "notice"}


def escape_data(value: str) -> str:
    return value.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")


def escape_property(value: str) -> str:
    return escape_data(value).replace(":", "%3A").replace(",", "%2C")


def format_finding(finding: Finding, *, witness: bool = False) -> str:
    properties = [f"file={escape_property(finding.file)}"]
    if finding.line:
        properties.append(f"line={finding.line}")
        if finding.column:
            properties.append(f"col={finding.column}")
    properties.append(f"title={escape_property(finding.rule)}")
    message = finding.message
    for note in finding.related:
        message += f"\n{note.location}: note: {note.message}"
    if witness and finding.witness is not None:
        message += f"\nwitness: {finding.witness.describe()}"
    return f"::{_COMMANDS[finding.severity]} {','.join(properties)}::{escape_data(message)}"


def format_input_error(error: InputError) -> str:
    """An unreadable input as an `::error` annotation on the file (and place) itself."""
    properties = [f"file={escape_property(error.file)}"] if error.file else []
    if error.line:
        properties.append(f"line={error.line}")
        if error.column:
            properties.append(f"col={error.column}")
    properties.append("title=unreadable input")
    return f"::error {','.join(properties)}::{escape_data(error.message)}"


def render(report: Report, *, witness: bool = False) -> str:
    lines = [format_input_error(e) for e in report.input_errors]
    lines += [format_finding(f, witness=witness) for f in report.findings]
    # Beyond --max-findings: one notice per rule, as the text report's "... and N more".
    lines += [
        f"::notice title={escape_property(rule)}::{escape_data(more_line(rule, count).strip())}"
        for rule, count in report.omitted_by_rule().items()
    ]
    return "".join(line + "\n" for line in lines)
