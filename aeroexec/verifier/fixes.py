"""Mechanical fixes (`aeroexec verify --fix`, `--diff`): edits of whole lines that leave
every other byte of the file as it was.

A fix is offered only where it is unambiguous:

* AX803 — a parameter-only key (`allowed_values`) indented as a key of the task, right
  after a `- parameter:` entry that has none: its lines are indented under that entry;
* AX001 — an unused suppression comment is removed (with the spaces before it; the
  whole line when the comment was alone on it), or, when it still silences other
  codes, only its unused codes;
* AX401 — a behavior preempted one-sidedly that declares no `incompatible_lists` of its
  own, when exactly one behavior list holds every behavior preempting it: the behavior
  gets `incompatible_lists: [THAT_LIST]`, which makes the preemption mutual; and a
  behavior that preempts through one list it names but is not in, when every behavior
  it preempts names that list too: it joins the list (a flow list `[A, B]` gets `, C`
  before its bracket, a block list one more `- C` line).

Fixes are applied in passes until none is left (at most `FIX_PASSES`), as ruff does:
a fix can make another possible (an AX401 fix leaves the `aeroexec: ignore[AX401]` on
its line unused, which AX001's fix then removes), and fixes of the same lines wait for
the next pass. The passes run on the fixed contents in memory (`fix_until_stable`):
`--diff` shows what all of them make and writes nothing, `--fix` writes the result.

The text is read as bytes and decoded as UTF-8; lines are cut at `\\n` only (a `\\r\\n`
stays in its line), and a file with other line breaks, tabs in the indentation it would
change, or edits that overlap gets no fix. Applying a fix replaces only the lines it
names.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

from aeroexec.catalog.formats import read_any_catalog
from aeroexec.catalog.model import Catalog
from aeroexec.errors import AeroexecError
from aeroexec.inputs import current_bytes, pending_contents
from aeroexec.verifier.findings import Finding, Report
from aeroexec.verifier.suppress import DIRECTIVE, EVERY, codes_of

FIXABLE = ("AX001", "AX401", "AX803")


@dataclass(frozen=True, slots=True)
class Edit:
    """Replace lines `first`..`last` (1-based, inclusive; `last == first - 1` inserts
    before `first`) by `text`."""

    first: int
    last: int
    text: str


@dataclass(frozen=True, slots=True)
class Fix:
    file: str
    rule: str
    line: int
    description: str
    edits: tuple[Edit, ...]


def split_lines(text: str) -> list[str]:
    """Lines with their endings, cut at `\\n` only; [] for a text with line breaks
    the loaders would count differently (a lone `\\r`, U+0085, U+2028, U+2029)."""
    if "\r" in text.replace("\r\n", "") or any(c in text for c in "\x85\u2028\u2029"):
        return []
    parts = text.split("\n")
    lines = [part + "\n" for part in parts[:-1]]
    if parts[-1]:
        lines.append(parts[-1])
    return lines


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip(" "))


def _blank_or_comment(line: str) -> bool:
    stripped = line.strip()
    return not stripped or stripped.startswith("#")


def _ending(lines: Sequence[str], index: int) -> str:
    line = lines[index] if 0 <= index < len(lines) else ""
    if line.endswith("\r\n"):
        return "\r\n"
    return "\n"


_PARAMETER_LINE = re.compile(r"\(line (\d+)\), which gets no ")
_PARAMETER_ITEM = re.compile(r"^( *)-( +)parameter\s*:")


def _misindented_key(finding: Finding, lines: Sequence[str]) -> Fix | None:
    found = _PARAMETER_LINE.search(finding.message)
    if found is None:  # the entry above already has the key: which one wins is a choice
        return None
    parameter, key = int(found[1]), finding.line
    if not (0 < parameter < key <= len(lines)):
        return None
    item = _PARAMETER_ITEM.match(lines[parameter - 1])
    key_line = lines[key - 1]
    indent = finding.column - 1
    if item is None or "\t" in key_line[: indent + 1] or _indent(key_line) != indent:
        return None
    dash, target = len(item[1]), len(item[1]) + 1 + len(item[2])
    if target <= indent:
        return None
    for between in lines[parameter : key - 1]:  # all part of the parameter's entry
        if not _blank_or_comment(between) and _indent(between) <= dash:
            return None
    last = key
    for index in range(key, len(lines)):  # the key's own value on the lines after it
        line = lines[index]
        if _blank_or_comment(line):
            continue
        if _indent(line) <= indent or "\t" in line[: _indent(line) + 1]:
            break
        last = index + 1
    shift = " " * (target - indent)
    moved = "".join(line if not line.strip() else shift + line for line in lines[key - 1 : last])
    return Fix(
        finding.file,
        finding.rule,
        finding.line,
        f"indent '{key_line.strip().split(':')[0]}' under '- parameter:' at line {parameter}",
        (Edit(key, last, moved),),
    )


def _one_sided(finding: Finding, lines: Sequence[str], catalog: Catalog) -> Fix | None:
    if len(finding.subjects) < 2:
        return None
    if " is preempted by " not in finding.message:
        return _one_sided_preemptor(finding, lines, catalog)
    victim, *preemptors = finding.subjects
    descriptor = catalog.behaviors.get(victim)
    if descriptor is None or "incompatible_lists" in descriptor.marks:
        return None
    holding = [name for name, lst in catalog.lists.items() if set(preemptors) <= set(lst.behaviors)]
    if len(holding) != 1:
        return None
    key = descriptor.mark.line
    if not (0 < key <= len(lines)):
        return None
    pattern = rf"^ *(- +)?behavior\s*:\s*['\"]?{re.escape(victim)}['\"]?\s*(#.*)?$"
    if re.match(pattern, lines[key - 1].rstrip("\r\n")) is None:
        return None  # a flow mapping, or a layout this fix does not know
    indent = descriptor.mark.column - 1
    last = key
    for index in range(key, len(lines)):  # the behavior's keys (and their values)
        line = lines[index]
        if _blank_or_comment(line):
            continue
        if _indent(line) < indent:
            break
        last = index + 1
    eol = _ending(lines, 0)
    added = f"{' ' * indent}incompatible_lists: [{holding[0]}]"
    edit = (
        Edit(last + 1, last, added + eol)
        if lines[last - 1].endswith("\n")
        else Edit(last, last, lines[last - 1] + eol + added)  # the file ends there, unended
    )
    return Fix(
        finding.file,
        finding.rule,
        finding.line,
        f"add 'incompatible_lists: [{holding[0]}]' to {victim}",
        (edit,),
    )


def _one_sided_preemptor(finding: Finding, lines: Sequence[str], catalog: Catalog) -> Fix | None:
    """A preempts its victims through one list L it names but is not in, and every
    victim names L too: A joins L, and they preempt it back."""
    preemptor, *victims = finding.subjects
    descriptor = catalog.behaviors.get(preemptor)
    if descriptor is None:
        return None
    through = [
        name
        for name in descriptor.incompatible_lists
        if name in catalog.lists and set(victims) <= set(catalog.lists[name].behaviors)
    ]
    if len(through) != 1:
        return None
    chosen = catalog.lists[through[0]]
    if preemptor in chosen.behaviors or not chosen.behaviors:
        return None
    if any(through[0] not in catalog.behaviors[v].incompatible_lists for v in victims):
        return None  # joining L would not make every victim preempt it back
    last_mark = chosen.marks.get(f"behaviors.{len(chosen.behaviors) - 1}")
    if last_mark is None or not (0 < last_mark.line <= len(lines)):
        return None
    line = lines[last_mark.line - 1]
    body = line.rstrip("\r\n")
    ending = line[len(body) :]
    last = chosen.behaviors[-1]
    item = re.match(rf"^( *)-( +)['\"]?{re.escape(last)}['\"]?\s*(#.*)?$", body)
    if item is not None:  # a block list: one more item line, indented as the last
        added = f"{item[1]}-{item[2]}{preemptor}{ending or _ending(lines, 0)}"
        text = line + added if ending else line + _ending(lines, 0) + added.rstrip("\r\n")
        edit = Edit(last_mark.line, last_mark.line, text)
    else:  # a flow list `[A, B]`: the name before its closing bracket
        start = last_mark.column - 1 + len(last)
        close = body.find("]", start)
        comment = body.find("#", start)
        if close < 0 or (0 <= comment < close) or "[" not in body[:start]:
            return None
        edit = Edit(
            last_mark.line,
            last_mark.line,
            body[:close].rstrip(" ") + f", {preemptor}" + body[close:] + ending,
        )
    return Fix(
        finding.file,
        finding.rule,
        finding.line,
        f"add {preemptor} to the list {chosen.name}",
        (edit,),
    )


def _unused_suppression(finding: Finding, lines: Sequence[str]) -> Fix | None:
    """Remove an unused suppression comment, or only its unused codes."""
    if not (0 < finding.line <= len(lines)):
        return None
    line = lines[finding.line - 1]
    body = line.rstrip("\r\n")
    ending = line[len(body) :]
    start = finding.column - 1
    found = DIRECTIVE.match(body, start) if 0 <= start < len(body) else None
    if found is None:
        return None  # the file changed since
    codes = codes_of(found)
    unused = set(finding.subjects)
    kept = [] if codes == EVERY else [c for c in codes if c not in unused]
    if kept:
        group = "list" if found["list"] is not None else "bracket"
        text = body[: found.start(group)] + ", ".join(kept) + body[found.end(group) :] + ending
        description = f"remove {', '.join(sorted(unused))} from the suppression comment"
        return Fix(
            finding.file,
            finding.rule,
            finding.line,
            description,
            (Edit(finding.line, finding.line, text),),
        )
    before, after = body[:start], body[found.end() :]
    if not before.strip() and not after.strip():
        text = ""  # the comment was the line
    elif not after.strip():
        text = before.rstrip(" \t") + ending
    elif not before.strip():
        text = before + after.lstrip(" \t") + ending
    else:
        text = before.rstrip(" \t") + "  " + after.lstrip(" \t") + ending
    return Fix(
        finding.file,
        finding.rule,
        finding.line,
        "remove the unused suppression comment",
        (Edit(finding.line, finding.line, text),),
    )


def fixes_for(findings: Iterable[Finding]) -> list[Fix]:
    """The unambiguous fixes of these findings, at most one edit per line of a file."""
    by_file: dict[str, list[Finding]] = {}
    for finding in findings:
        if finding.rule in FIXABLE and finding.file and finding.line > 0:
            by_file.setdefault(finding.file, []).append(finding)
    fixes: list[Fix] = []
    for file, found in by_file.items():
        lines = _read_lines(file)
        if not lines:
            continue
        catalog: Catalog | None = None
        if any(f.rule == "AX401" for f in found):
            try:
                loaded = read_any_catalog(file)
            except AeroexecError:
                loaded = None
            catalog = loaded if isinstance(loaded, Catalog) else None
        taken: set[int] = set()
        for finding in found:
            fix = (
                _misindented_key(finding, lines)
                if finding.rule == "AX803"
                else _unused_suppression(finding, lines)
                if finding.rule == "AX001"
                else _one_sided(finding, lines, catalog)
                if catalog is not None
                else None
            )
            if fix is None:
                continue
            touched = {
                n
                for edit in fix.edits
                for n in range(edit.first - 1, max(edit.last, edit.first) + 1)
            }
            if touched & taken:
                continue  # two fixes about the same lines: keep the first
            taken |= touched
            fixes.append(fix)
    return fixes


def _read_lines(file: str) -> list[str]:
    try:
        text = current_bytes(file).decode("utf-8")
    except (OSError, UnicodeDecodeError):
        return []
    return split_lines(text)


def apply_fixes(text: str, fixes: Sequence[Fix]) -> str:
    """`text` with the fixes' edits (of one file) applied; other lines untouched."""
    lines = split_lines(text)
    edits = sorted((e for fix in fixes for e in fix.edits), key=lambda e: e.first, reverse=True)
    for edit in edits:
        lines[edit.first - 1 : edit.last] = [edit.text]
    return "".join(lines)


def fixed_files(fixes: Sequence[Fix]) -> dict[str, tuple[bytes, bytes]]:
    """file -> (its bytes now, its bytes fixed)."""
    by_file: dict[str, list[Fix]] = {}
    for fix in fixes:
        by_file.setdefault(fix.file, []).append(fix)
    result: dict[str, tuple[bytes, bytes]] = {}
    for file, own in by_file.items():
        before = current_bytes(file)
        after = apply_fixes(before.decode("utf-8"), own).encode("utf-8")
        if after != before:
            result[file] = (before, after)
    return result


def unified_diff(file: str, before: bytes, after: bytes) -> str:
    old = before.decode("utf-8").splitlines(keepends=True)
    new = after.decode("utf-8").splitlines(keepends=True)
    lines = difflib.unified_diff(old, new, f"a/{file}", f"b/{file}")
    return "".join(line if line.endswith("\n") else line + "\n" for line in lines)


#: Passes of fixes at most (a pass applies the fixes that touch distinct lines).
FIX_PASSES = 10


@dataclass(frozen=True)
class FixRun:
    """What the passes of fixes made: the report on the fixed contents, and each
    changed file's bytes before and after (nothing is written)."""

    report: Report
    before: dict[str, bytes]
    after: dict[str, bytes]
    applied: int
    passes: int


def fix_until_stable(
    verify_again: Callable[[], Report], report: Report, passes: int = FIX_PASSES
) -> FixRun:
    """Apply the fixes of `report`, verify the fixed contents again (`verify_again`,
    which reads them in memory), and so on until no fix is left or `passes` ran."""
    contents: dict[str, bytes] = {}
    before: dict[str, bytes] = {}
    applied = done = 0
    with pending_contents(contents):
        while done < passes:
            fixes = fixes_for(report.findings)
            changes = fixed_files(fixes)
            if not changes:
                break
            for file, (now, fixed) in changes.items():
                before.setdefault(file, now)
                contents[file] = fixed
            applied += sum(1 for fix in fixes if fix.file in changes)
            done += 1
            report = verify_again()
    after = {file: data for file, data in contents.items() if data != before[file]}
    return FixRun(report, {f: before[f] for f in after}, after, applied, done)
