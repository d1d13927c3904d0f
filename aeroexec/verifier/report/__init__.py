"""Reporters: one module per output format, each a pure function Report -> str."""

from __future__ import annotations

from collections.abc import Callable

from aeroexec.verifier.findings import Report
from aeroexec.verifier.report import github, json, sarif, text

Formatter = Callable[..., str]

FORMATS: dict[str, str] = {
    "text": "compiler-style lines `file:line:col: severity CODE message` and a summary",
    "json": "one JSON object: findings and summary",
    "sarif": "SARIF 2.1.0, for code-scanning upload",
    "github": "GitHub Actions workflow annotations (::error file=...::message)",
}


def render(report: Report, fmt: str, *, witness: bool = False, color: bool = False) -> str:
    """The report in format `fmt` (one of FORMATS); ValueError for another name."""
    if fmt == "text":
        return text.render(report, witness=witness, color=color)
    if fmt == "json":
        return json.render(report)
    if fmt == "sarif":
        return sarif.render(report)
    if fmt == "github":
        return github.render(report, witness=witness)
    raise ValueError(f"unknown format {fmt!r}")


__all__ = ["FORMATS", "render"]
