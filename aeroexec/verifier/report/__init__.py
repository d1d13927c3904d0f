"""Reporters: one module per output format, each a pure function Report -> str.

A format's module is imported when it is rendered: the text report (the default) does not
load SARIF's rule documentation (start-up time)."""

from __future__ import annotations

import importlib
from collections.abc import Callable

from aeroexec.verifier.findings import Report

Formatter = Callable[..., str]

FORMATS: dict[str, str] = {
    "text": "compiler-style lines `file:line:col: severity CODE message` and a summary",
    "json": "one JSON object: findings and summary",
    "sarif": "SARIF 2.1.0, for code-scanning upload",
    "github": "GitHub Actions workflow annotations (::error file=...::message)",
}


def render(report: Report, fmt: str, *, witness: bool = False, color: bool = False) -> str:
    """The report in format `fmt` (one of FORMATS); ValueError for another name."""
    if fmt not in FORMATS:
        raise ValueError(f"unknown format {fmt!r}")
    reporter = importlib.import_module(f"{__name__}.{fmt}")
    if fmt == "text":
        return reporter.render(report, witness=witness, color=color)  # type: ignore[no-any-return]
    if fmt == "github":
        return reporter.render(report, witness=witness)  # type: ignore[no-any-return]
    return reporter.render(report)  # type: ignore[no-any-return]


__all__ = ["FORMATS", "render"]
