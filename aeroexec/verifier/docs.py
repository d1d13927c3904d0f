"""docs/rules.md, generated from the registry.

    python -m aeroexec.verifier.docs > docs/rules.md

`tests/test_verifier_docs.py` fails when docs/rules.md is not what this prints.
"""

from __future__ import annotations

import sys

from aeroexec.verifier.registry import AREAS, Rule, all_rules

INTRO = """\
# aeroexec verify: rules

Generated from the rule registry (`python -m aeroexec.verifier.docs > docs/rules.md`);
do not edit by hand. `aeroexec verify --explain CODE` prints the same text.

Codes by range: AX1xx are reported by the catalog loader and passed through by the
verifier; AX2xx references; AX3xx capability consistency; AX4xx incompatibility;
AX5xx start order; AX6xx behavior properties; AX7xx missions (`--mission`); AX9xx the
catalog against the behavior code that runs it (when the project declares its behaviors:
`--behaviors`, `[tool.aeroexec] behaviors`, entry points).
Rules marked *witness* attach, where one exists, the shortest activation sequence that
makes the problem happen in the executive (`--witness`, and `witness` in JSON/SARIF).
"""


def _row(rule: Rule) -> str:
    severity = rule.severity.value if rule.severity else "as reported"
    witness = "yes" if rule.witness else ""
    return f"| [{rule.code}](#{rule.code.lower()}) | {rule.name} | {severity} | {witness} |"


def render_rules_markdown() -> str:
    rules = all_rules()
    lines = [INTRO, "| code | name | severity | witness |", "| --- | --- | --- | --- |"]
    lines += [_row(rule) for rule in rules]
    area = None
    for rule in rules:
        if rule.code[:3] != area:
            area = rule.code[:3]
            lines += ["", f"## {AREAS[area]}"]
        severity = rule.severity.value if rule.severity else "as reported"
        lines += ["", f"### {rule.code}", "", f"`{rule.name}` — {severity}", "", rule.doc]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":  # pragma: no cover - exercised by the docs test
    sys.stdout.write(render_rules_markdown())
