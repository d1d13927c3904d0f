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
from pathlib import Path

_DIRECTIVE = re.compile(
    r"#\s*(?:noqa|aeroexec:\s*ignore)"
    r"(?:\s*:\s*(?P<list>[A-Za-z0-9]+(?:\s*,\s*[A-Za-z0-9]+)*)|\[(?P<bracket>[^\]]*)\])?",
    re.IGNORECASE,
)

#: A suppression that silences every code.
EVERY = ("",)


def _codes(comment: str) -> tuple[str, ...] | None:
    found = _DIRECTIVE.search(comment)
    if found is None:
        return None
    listed = found["list"] if found["list"] is not None else found["bracket"]
    if listed is None or not listed.strip():
        return EVERY
    return tuple(part.strip().upper() for part in listed.split(",") if part.strip())


class Suppressions:
    """The suppression comments of the files findings are reported in (read once each)."""

    def __init__(self) -> None:
        self._files: dict[str, dict[int, tuple[str, ...]]] = {}

    def suppressed(self, file: str, line: int, code: str) -> bool:
        if line <= 0 or not file:
            return False
        codes = self._comments(file).get(line)
        return codes is not None and any(c == "" or code.startswith(c) for c in codes)

    def _comments(self, file: str) -> dict[int, tuple[str, ...]]:
        if file not in self._files:
            self._files[file] = _read_comments(file)
        return self._files[file]


def _read_comments(file: str) -> dict[int, tuple[str, ...]]:
    """Line -> the codes suppressed there (a directive alone on its line also covers
    the next line)."""
    try:
        text = Path(file).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return {}
    folded = text.lower()  # one pass; a case-insensitive regex is 20 times slower here
    if "noqa" not in folded and "aeroexec:" not in folded:
        return {}  # the common case: a large catalog without a directive
    comments: list[tuple[int, str, bool]] = []  # line, comment, alone on its line
    lines = text.splitlines()
    if file.endswith(".py"):
        try:
            for token in tokenize.generate_tokens(io.StringIO(text).readline):
                if token.type == tokenize.COMMENT:
                    row, column = token.start
                    alone = not lines[row - 1][:column].strip()
                    comments.append((row, token.string, alone))
        except (tokenize.TokenError, SyntaxError, IndexError):
            return {}
    else:
        for number, line in enumerate(lines, start=1):
            index = line.find("#")
            if index >= 0:
                comments.append((number, line[index:], not line[:index].strip()))
    found: dict[int, tuple[str, ...]] = {}
    for row, comment, alone in comments:
        codes = _codes(comment)
        if codes is None:
            continue
        found[row] = found.get(row, ()) + codes
        if alone:
            found[row + 1] = found.get(row + 1, ()) + codes
    return found
