"""Suppression in place: a comment on the line a finding is reported at.

* in a mission script, as ruff: `# noqa: AX711` (several codes with commas; a bare
  `# noqa` silences every finding on its line);
* in a catalog (YAML), `# aeroexec: ignore[AX401]` (several codes with commas; a bare
  `# aeroexec: ignore` silences every finding on its line). The comment may also stand
  alone on the line just above the finding's line.

Both spellings are understood in both kinds of file. In Python only real comments
count (the tokenizer finds them: a `# noqa` inside a string is text). Codes may be
prefixes (`AX7`), as the selection options take them.
"""

from __future__ import annotations

import io
import re
import tokenize
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

from aeroexec.catalog.model import Severity
from aeroexec.errors import Mark
from aeroexec.inputs import current_bytes
from aeroexec.verifier.findings import Finding
from aeroexec.verifier.registry import Rule, all_rules, register

#: A suppression comment; `list` (after `noqa:`) or `bracket` (in `ignore[...]`) holds
#: its codes, neither a blanket one.
DIRECTIVE = re.compile(
    r"#\s*(?:noqa|aeroexec:\s*ignore)"
    r"(?:\s*:\s*(?P<list>[A-Za-z0-9]+(?:\s*,\s*[A-Za-z0-9]+)*)|\[(?P<bracket>[^\]]*)\])?",
    re.IGNORECASE,
)

#: A suppression that silences every code.
EVERY = ("",)

_UNUSED_DOC = """A suppression comment (`# noqa: AX711` in a mission, `# aeroexec:
ignore[AX401]` in a catalog, or a bare one) that silences no finding of this run, as
ruff's RUF100: the problem it was written for is gone (or was never on that line), and
the comment would silently hide the next, different problem there. In flight: nothing
at first; then the new problem the comment hides on that line (a call a later edit
breaks, a list a later edit empties) flies unreported. A code that names no
rule is reported too. Codes of rules the run does not select count as unused, as in
ruff (so select AX001 with the rules its comments name). Reported at the comment;
`--fix` removes it (only the unused codes of a comment that still silences others; the
whole line of a comment alone on its line). A comment that names AX001 is never
reported. Fix: remove the comment."""

UNUSED = register(
    Rule(
        "AX001",
        "unused-suppression",
        Severity.WARNING,
        " ".join(_UNUSED_DOC.split()),
        "suppression",
    )
)


def _codes(comment: str) -> tuple[str, ...] | None:
    found = DIRECTIVE.search(comment)
    if found is None:
        return None
    return codes_of(found)


def codes_of(found: re.Match[str]) -> tuple[str, ...]:
    """The codes a matched directive names (upper case), `EVERY` for a blanket one."""
    listed = found["list"] if found["list"] is not None else found["bracket"]
    if listed is None or not listed.strip():
        return EVERY
    return tuple(part.strip().upper() for part in listed.split(",") if part.strip())


@dataclass(frozen=True, slots=True)
class Directive:
    """One suppression comment: where its `#` is, the codes it names (`EVERY` for a
    blanket one), and whether it stands alone on its line (it then covers the next
    line too)."""

    file: str
    line: int
    column: int
    codes: tuple[str, ...]
    alone: bool
    #: The directive as written, from its hash sign on.
    text: str = ""


class Suppressions:
    """The suppression comments of the files findings are reported in (read once each),
    and which of their codes silenced something."""

    def __init__(self) -> None:
        self._files: dict[str, dict[int, list[Directive]]] = {}
        self._directives: dict[str, list[Directive]] = {}
        self._used: dict[Directive, set[str]] = {}

    def suppressed(self, file: str, line: int, code: str) -> bool:
        if line <= 0 or not file:
            return False
        hit = False
        for directive in self._comments(file).get(line, ()):
            for selector in directive.codes:
                if selector == "" or code.startswith(selector):
                    self._used.setdefault(directive, set()).add(selector)
                    hit = True
        return hit

    def _comments(self, file: str) -> dict[int, list[Directive]]:
        if file not in self._files:
            directives = _read_directives(file)
            by_line: dict[int, list[Directive]] = {}
            for directive in directives:
                by_line.setdefault(directive.line, []).append(directive)
                if directive.alone:
                    by_line.setdefault(directive.line + 1, []).append(directive)
            self._files[file] = by_line
            self._directives[file] = directives
        return self._files[file]

    def unused(self, files: Iterable[str]) -> Iterator[Finding]:
        """An AX001 finding for each directive of `files` that silenced nothing (or
        names codes that silenced nothing), in file order."""
        known: tuple[str, ...] | None = None
        for file in dict.fromkeys(files):
            self._comments(file)
            for directive in self._directives[file]:
                if any(c and UNUSED.code.startswith(c) for c in directive.codes):
                    continue  # a comment naming AX001 keeps itself
                used = self._used.get(directive, set())
                where = "on this line or the next" if directive.alone else "on this line"
                if directive.codes == EVERY:
                    if not used:
                        why = f"a blanket one that silences no finding {where}"
                        yield _unused(directive, (directive.text,), why)
                    continue
                if known is None:
                    known = tuple(rule.code for rule in all_rules())
                unknown = [c for c in directive.codes if not any(k.startswith(c) for k in known)]
                idle = [c for c in directive.codes if c not in used and c not in unknown]
                parts = []
                if idle:
                    verb = "silences" if len(idle) == 1 else "silence"
                    parts.append(f"{', '.join(idle)} {verb} no finding {where}")
                if unknown:
                    what = "is not a rule code" if len(unknown) == 1 else "are not rule codes"
                    parts.append(f"{', '.join(unknown)} {what}")
                if parts:
                    yield _unused(directive, (*idle, *unknown), "; ".join(parts))


def _unused(directive: Directive, codes: tuple[str, ...], why: str) -> Finding:
    return Finding.at(
        UNUSED.code,
        Severity.WARNING,
        f"unused suppression: {why}",
        Mark(directive.file, directive.line, directive.column),
        codes,
    )


def _read_directives(file: str) -> list[Directive]:
    """The suppression comments of a file, in order."""
    try:
        text = current_bytes(file).decode("utf-8")
    except (OSError, UnicodeDecodeError):
        return []
    folded = text.lower()  # one pass; a case-insensitive regex is 20 times slower here
    if "noqa" not in folded and "aeroexec:" not in folded:
        return []  # the common case: a large catalog without a directive
    comments: list[tuple[int, int, str, bool]] = []  # line, column, comment, alone
    lines = text.splitlines()
    if file.endswith(".py"):
        try:
            for token in tokenize.generate_tokens(io.StringIO(text).readline):
                if token.type == tokenize.COMMENT:
                    row, column = token.start
                    alone = not lines[row - 1][:column].strip()
                    comments.append((row, column, token.string, alone))
        except (tokenize.TokenError, SyntaxError, IndexError):
            return []
    else:
        for number, line in enumerate(lines, start=1):
            index = line.find("#")
            if index >= 0:
                comments.append((number, index, line[index:], not line[:index].strip()))
    found: list[Directive] = []
    for row, column, comment, alone in comments:
        match = DIRECTIVE.search(comment)
        if match is None:
            continue
        found.append(
            Directive(file, row, column + match.start() + 1, codes_of(match), alone, match.group(0))
        )
    return found
