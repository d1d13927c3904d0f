"""One JSON object: `{"findings": [...], "summary": {"errors", "warnings", "infos"}}`."""

from __future__ import annotations

import json as _json

from aeroexec.verifier.findings import Report


def render(report: Report) -> str:
    return _json.dumps(report.to_dict(), indent=2, ensure_ascii=False) + "\n"
