"""docs/rules.md, generated from the registry.

    python -m aeroexec.verifier.docs > docs/rules.md

`tests/test_verifier_docs.py` fails when docs/rules.md is not what this prints.
"""

from __future__ import annotations

import sys
from functools import cache
from importlib import metadata
from pathlib import Path

from aeroexec.verifier.registry import AREAS, Rule, all_rules

#: docs/rules.md of a source checkout (an editable install), next to the package.
_LOCAL_RULES_MD = Path(__file__).resolve().parents[2] / "docs" / "rules.md"


@cache
def _rules_doc() -> str | None:
    """Where docs/rules.md is: the `Documentation` project URL of the installed
    distribution (`.../rules.md`), else the file in a source checkout, else unknown."""
    try:
        urls = metadata.metadata("aeroexec").get_all("Project-URL") or []
    except metadata.PackageNotFoundError:
        urls = []
    for entry in urls:
        label, _, url = entry.partition(",")
        if label.strip().lower() == "documentation" and url.strip():
            return url.strip().rstrip("/") + "/rules.md"
    if _LOCAL_RULES_MD.is_file():
        return _LOCAL_RULES_MD.as_uri()
    return None


def rule_doc_url(code: str) -> str | None:
    """The URL of a rule's paragraph in docs/rules.md (its `### CODE` anchor)."""
    base = _rules_doc()
    return None if base is None else f"{base}#{code.lower()}"


INTRO = """\
# aeroexec verify: rules

Generated from the rule registry (`python -m aeroexec.verifier.docs > docs/rules.md`);
do not edit by hand. `aeroexec verify --list-rules` lists them, `aeroexec verify --explain
CODE` prints the same text.

Codes by range: AX0xx suppression comments that silence nothing (ruff's RUF100); AX1xx
are reported by the catalog loader and passed through by the verifier; AX2xx
references; AX3xx capability consistency; AX4xx incompatibility; AX5xx start order;
AX6xx behavior properties; AX7xx missions (`--mission`; AX75x the signals
of their property files, `--spec`); AX8xx the Aerostack 4.x task catalogs of 2020-2021
(AX80x from their loader, AX81x-AX82x rules, judged as the 2021 constraint-based
coordinator, cvar-upm/coordinator_cbc, would); AX9xx the catalog against the behavior
code that runs it (when the project declares its behaviors: `--behaviors`,
`[tool.aeroexec] behaviors`, entry points).
Rules marked *witness* attach, where one exists, the shortest activation sequence that
makes the problem happen in the executive (`--witness`, and `witness` in JSON/SARIF);
for task catalogs, the shortest `start_task` sequence on a model of that coordinator
(`aeroexec run` runs behavior catalogs only: a task witness is replayed on that model, and
says so).

## Choosing, silencing and fixing findings (as with ruff)

- **What is checked.** `aeroexec verify CATALOG... -m MISSION...`; without either, the
  `catalogs` and `missions` of `[tool.aeroexec.verify]` in the nearest `pyproject.toml`
  (or `aeroexec.toml`), else its `catalog`. Missions are Python scripts (`.py`) or
  Aerostack behavior-tree missions (`.yaml`, `nodes:`): against a task catalog on the
  task coordinator's model (AX716, AX717), against a behavior catalog as the flow a
  Python mission folds to (a node waited for is `execute_behavior`, one not waited for
  `activate_behavior`), run in the executive. A behavior-tree file given as a CATALOG is
  recognized as a mission.
- **Which rules.** `--select`, `--extend-select` and `--ignore` take codes or prefixes
  (`AX7`, `AX71`, `AX711`, `ALL`), comma-separated or repeated. The project's `select`,
  `extend-select` and `ignore` are applied first, then the command line's: a `select`
  starts again from what it names, `extend-select` adds, `ignore` removes; within one
  layer the most specific selector wins, and an ignore wins a tie. `per-file-ignores =
  {"missions/legacy_*.py" = ["AX7"]}` drops codes for the files a pattern matches
  (relative to the configuration's directory).
- **Suppression in place.** `# noqa: AX711` (or a bare `# noqa`) on the line of a mission
  finding; `# aeroexec: ignore[AX401]` (or a bare `# aeroexec: ignore`) on the line of a
  catalog finding, or alone on the line above it. In Python only real comments count
  (not text in a string). The summary line counts what was suppressed in place. A
  comment that silences nothing (or names a code that is no rule) is AX001, as ruff's
  RUF100, and `--fix` removes it.
- **Counts.** `--statistics` prints, instead of the findings, how many each rule has
  (count, code, name; `-f json` too), most first.
- **Fixes.** `--diff` prints the mechanical fixes as a unified diff and changes nothing
  (exit 1 when there is one); `--fix` applies them and reports what remains. A fix is
  offered only where it is unambiguous: AX001 (an unused suppression comment, or its
  unused codes, removed), AX803 (a parameter key indented as a task key,
  right after a `- parameter:` entry without one, is indented under it) and AX401 (a
  behavior preempted one-sidedly that has no `incompatible_lists` gets the one list
  that holds every behavior preempting it; a behavior preempting through one list it
  names but is not in joins that list, when everything it preempts names it too).
  As ruff does, fixes run again on the fixed text until none is left (at most 10
  passes): fixes of the same lines wait for the next pass, and a fix can make another
  possible (GO_TO given the list that makes its preemption mutual leaves the
  `aeroexec: ignore[AX304]` on its line silencing nothing, which the next pass
  removes). The passes run in memory: `--diff` shows what all of them make, `--fix`
  writes it. A fix replaces whole lines and leaves every other byte of the file as it
  was (line endings, a missing final newline, the file's
  mode); the file is replaced whole or not at all.
- **Call paths.** A mission finding inside a helper function carries the calls that
  lead to it, innermost first, as a compiler's notes: `m.py:9:5: note: in fly(), called
  from here` in text, `related` in JSON, `relatedLocations` in SARIF.
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
