"""`aeroexec report merge`: the JSON reports of a run's shards, put back together.

The merged results are the ones the unsharded run would have given, in its order, so
they render (text, JSON, JUnit) to the same bytes. A merge that could not be whole is
refused rather than presented as whole: a shard missing or given twice, shards of
different corpora (another checkout), settings (another catalog) or shard counts.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from aeroexec.errors import Mark, ReportError
from aeroexec.replay.diff import Difference, DiffResult, Tolerance
from aeroexec.replay.engine import ReplayResult
from aeroexec.replay.report import replay_json
from aeroexec.replay.shard import SHARD_FORMAT, ShardSlice

#: What `replay_recording` calls the two runs it compares.
BASE_NAME, NEW_NAME = "the recording", "the replay"


@dataclass(frozen=True, slots=True)
class ShardReport:
    """One shard's JSON report, read."""

    path: str
    index: int
    count: int
    corpus: str
    total: int
    positions: tuple[int, ...]
    settings: dict[str, Any]
    results: tuple[ReplayResult, ...]


def shard_json(results: Sequence[ReplayResult], part: ShardSlice) -> str:
    """A shard's JSON report: the replay report of its recordings, plus the `shard`
    block that lets `merge_shards` put the run back together."""
    document = json.loads(replay_json(results))
    document["shard"] = part.block()
    return json.dumps(document, indent=2)


def result_from_dict(data: dict[str, Any], tolerance: Tolerance) -> ReplayResult:
    """The inverse of `ReplayResult.as_dict` (what the report renderings use of it).
    `KeyError`/`TypeError`/`ValueError` when `data` is not such a dict."""
    error = data["error"]
    diff = None
    if error is None:
        differences = tuple(
            Difference(
                kind=str(d["kind"]),
                message=str(d["message"]),
                command=d["command"],
                label=str(d["label"]),
                base_index=d["base_index"],
                new_index=d["new_index"],
                line=d.get("line"),
            )
            for d in data["differences"]
        )
        diff = DiffResult(
            BASE_NAME,
            NEW_NAME,
            differences,
            int(data["compared_commands"]),
            tolerance,
            mission=str(data.get("mission") or ""),
        )
    return ReplayResult(
        recording=str(data["recording"]),
        mode=data["mode"],
        catalog=str(data["catalog"]),
        catalog_recorded=bool(data["catalog_recorded"]),
        diff=diff,
        error=None if error is None else str(error),
        output=data["output"],
        notes=tuple(str(n) for n in data["notes"]),
        code_changes=tuple(str(c) for c in data.get("code_changes", ())),
        properties=_verdicts(data.get("properties")),
    )


def _verdicts(data: Any) -> dict[str, Any] | None:
    """A recording's property verdicts, as `replay --spec` wrote them (checked: each has
    what the reports render from it)."""
    if data is None:
        return None
    for verdict in data["verdicts"]:
        for key in ("property", "status", "severity", "defined_at", "formula", "message"):
            if not isinstance(verdict[key], str):
                raise TypeError(f"property verdict {key!r} is not text")
    if not isinstance(data["recording"], str):
        raise TypeError("property verdicts' recording is not text")
    return dict(data)


def _tolerance(settings: dict[str, Any]) -> Tolerance:
    return Tolerance(float(settings["tolerance_s"]), float(settings["position_tolerance_m"]))


def read_shard(path: str | Path) -> ShardReport:
    """A shard's JSON report (`aeroexec replay --shard K/N --format json`)."""
    name = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise ReportError(f"cannot read: {reason}", Mark(name)) from None
    try:
        document = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ReportError(f"not JSON: {exc.msg}", Mark(name, exc.lineno, exc.colno)) from None
    block = document.get("shard") if isinstance(document, dict) else None
    if not isinstance(block, dict):
        raise ReportError(
            "not a shard report (made by `aeroexec replay ... --shard K/N --format json`)",
            Mark(name),
        )
    if block.get("format") != SHARD_FORMAT:
        raise ReportError(
            f"shard report format {block.get('format')!r}, this aeroexec reads "
            f"{SHARD_FORMAT}: merge with the aeroexec that replayed",
            Mark(name),
        )
    try:
        settings = dict(block["settings"])
        tolerance = _tolerance(settings)
        results = tuple(result_from_dict(r, tolerance) for r in document["recordings"])
        report = ShardReport(
            path=name,
            index=int(block["index"]),
            count=int(block["count"]),
            corpus=str(block["corpus"]),
            total=int(block["total"]),
            positions=tuple(int(p) for p in block["positions"]),
            settings=settings,
            results=results,
        )
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise ReportError(f"malformed shard report: {_what(exc)}", Mark(name)) from None
    if len(report.positions) != len(report.results):
        raise ReportError(
            f"malformed shard report: {len(report.results)} recordings for "
            f"{len(report.positions)} positions",
            Mark(name),
        )
    return report


def _what(exc: Exception) -> str:
    if isinstance(exc, KeyError):
        return f"missing {exc.args[0]!r}"
    return str(exc) or type(exc).__name__


def merge_shards(reports: Sequence[ShardReport]) -> list[ReplayResult]:
    """Every shard's results, in the order of the whole run. `ReportError` when the shards
    do not make exactly one whole run."""
    if not reports:
        raise ReportError("no shard reports to merge")
    first = reports[0]
    for report in reports[1:]:
        for field, what in (
            ("count", "shard counts"),
            ("corpus", "corpora (the recordings each shard saw differ)"),
            ("total", "corpus sizes"),
            ("settings", "settings (catalog, mode or tolerances)"),
        ):
            if getattr(report, field) != getattr(first, field):
                raise ReportError(
                    f"shards of different runs: {what} differ from {first.path}",
                    Mark(report.path),
                )
    seen: dict[int, str] = {}
    for report in reports:
        if not 1 <= report.index <= first.count:
            raise ReportError(f"shard {report.index}/{report.count} is out of range")
        if report.index in seen:
            raise ReportError(
                f"shard {report.index}/{first.count} given twice (also {seen[report.index]})",
                Mark(report.path),
            )
        seen[report.index] = report.path
    missing = [str(i) for i in range(1, first.count + 1) if i not in seen]
    if missing:
        raise ReportError(
            f"shard(s) {', '.join(missing)} of {first.count} missing: "
            "the merged report would not be whole"
        )
    ordered: list[ReplayResult | None] = [None] * first.total
    for report in reports:
        for position, result in zip(report.positions, report.results, strict=True):
            if not 0 <= position < first.total or ordered[position] is not None:
                raise ReportError(
                    f"malformed shard report: position {position} is out of range or taken",
                    Mark(report.path),
                )
            ordered[position] = result
    holes = sum(r is None for r in ordered)
    if holes:
        raise ReportError(f"the shards hold {first.total - holes} of {first.total} recordings")
    return [r for r in ordered if r is not None]
