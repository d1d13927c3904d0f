"""The tokens of a formula, as RTAMT's STL lexer (0.4.10) cuts them.

The language is RTAMT's (docs/properties.md#the-engine), so the tokens are too: the
longest match wins and a keyword beats a name of the same length, which makes `G`, `F`,
`U`, `s` and `ms` operators and units while `Go`, `active_F` and `altitude/2` are names
(a name may hold `.` and `/`). Comments (`/* */`, `//`) are skipped like whitespace.

RTAMT's specification language is more than expressions: declarations, `const`, and
`from M import T`, which imports a Python module. Those words and the punctuation they
need come out as `forbidden` tokens, so that the caller can refuse them at their column;
nothing here or in the parser gives them a meaning.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

#: Words with a meaning in a formula, by kind of token.
KEYWORDS: dict[str, str] = {
    **dict.fromkeys(("abs", "sqrt", "exp", "pow"), "function"),
    **dict.fromkeys(("s", "ms", "us", "ns"), "unit"),
    **dict.fromkeys(("not", "always", "G", "eventually", "F"), "prefix"),
    **dict.fromkeys(("historically", "H", "once", "O", "prev", "Y", "next", "X"), "prefix"),
    **dict.fromkeys(("rise", "fall"), "edge"),
    **dict.fromkeys(("and", "or", "implies", "iff", "xor"), "binary"),
    **dict.fromkeys(("until", "U", "unless", "W", "since", "S"), "binary"),
    # Literals RTAMT's lexer knows and its expressions do not take: a syntax error.
    **dict.fromkeys(("true", "TRUE", "false", "FALSE"), "word"),
}
#: RTAMT's words for what is not an expression (declarations, imports, ROS topics).
FORBIDDEN_WORDS = frozenset(
    {
        *("ps", "topic", "import", "input", "output", "internal", "const", "assertion"),
        *("real", "float", "long", "complex", "int", "bool", "specification", "from"),
        *("s_next", "s_prev"),
    }
)
#: Operator spellings, longest first (the longest match wins).
_OPERATORS = (
    "!==",
    "<->",
    "==",
    ">=",
    "<=",
    "->",
    ">",
    "<",
    "!",
    "|",
    "&",
    "-",
    "+",
    "*",
    "/",
    "(",
    ")",
    "[",
    "]",
    ":",
    ",",
)
#: Punctuation of RTAMT's declarations: never part of an expression.
_FORBIDDEN_PUNCTUATION = frozenset("{};.@=")
#: Symbol spellings normalized to the word operators they stand for.
_SYNONYMS = {"!": "not", "|": "or", "&": "and", "<->": "iff", "->": "implies"}

_DIGITS = r"[0-9](?:[0-9_]*[0-9])?"
_EXPONENT = r"[eE][+-]?[0-9]+"
_REAL = re.compile(
    rf"{_DIGITS}\.(?:{_DIGITS})?(?:{_EXPONENT})?|\.{_DIGITS}(?:{_EXPONENT})?|{_DIGITS}{_EXPONENT}"
)
_INTEGER = re.compile(
    r"0[xX][0-9a-fA-F](?:[0-9a-fA-F_]*[0-9a-fA-F])?|0[bB][01](?:[01_]*[01])?|0|[1-9](?:[0-9_]*[0-9])?"
)
_NAME = re.compile(r"[A-Za-z_$][A-Za-z_$0-9./]*")
_SPACE = re.compile(r"[ \t\r\f]+")


@dataclass(frozen=True, slots=True)
class Token:
    """`kind`: number, name, function, unit, prefix, edge, binary, compare, punct, word,
    forbidden or end. `text`: as written (synonyms such as `&` as their word in `op`)."""

    kind: str
    text: str
    line: int  # 1-based, in the formula's text
    column: int  # 0-based, in its line

    @property
    def op(self) -> str:
        return _SYNONYMS.get(self.text, self.text)


class FormulaSyntaxError(Exception):
    """A mistake at (line, column) of a formula's text; formula.py places it in the file."""

    def __init__(self, message: str, line: int, column: int) -> None:
        super().__init__(message)
        self.message, self.line, self.column = message, line, column


def tokenize(text: str) -> list[Token]:
    """`text` as tokens, ending with an `end` token at the end of the text."""
    out: list[Token] = []
    pos, line, line_start = 0, 1, 0
    while pos < len(text):
        column = pos - line_start
        char = text[pos]
        if char == "\n":
            pos, line, line_start = pos + 1, line + 1, pos + 1
            continue
        if space := _SPACE.match(text, pos):
            pos = space.end()
            continue
        if text.startswith("/*", pos):
            close = text.find("*/", pos + 2)
            if close < 0:
                raise FormulaSyntaxError("unterminated comment", line, column)
            if newlines := text.count("\n", pos, close):
                line, line_start = line + newlines, text.rfind("\n", pos, close) + 1
            pos = close + 2
            continue
        if text.startswith("//", pos):
            end = text.find("\n", pos)
            pos = len(text) if end < 0 else end
            continue
        real, integer = _REAL.match(text, pos), _INTEGER.match(text, pos)
        number = max((m for m in (integer, real) if m), key=lambda m: m.end(), default=None)
        if number:
            out.append(Token("number", number.group(), line, column))
            pos = number.end()
            continue
        if name := _NAME.match(text, pos):
            word = name.group()
            kind = "forbidden" if word in FORBIDDEN_WORDS else KEYWORDS.get(word, "name")
            out.append(Token(kind, word, line, column))
            pos = name.end()
            continue
        if text.startswith("!=", pos) and not text.startswith("!==", pos):
            raise FormulaSyntaxError("'not equal' is written '!==' in this language", line, column)
        spelled = next((op for op in _OPERATORS if text.startswith(op, pos)), None)
        if spelled is not None:
            kind = "punct"
            if spelled in ("!==", "==", ">=", "<=", ">", "<"):
                kind = "compare"
            elif spelled in _SYNONYMS:
                kind = "prefix" if spelled == "!" else "binary"
            elif spelled in "-+*/":
                kind = "binary"
            out.append(Token(kind, spelled, line, column))
            pos += len(spelled)
            continue
        if char in _FORBIDDEN_PUNCTUATION:
            out.append(Token("forbidden", char, line, column))
            pos += 1
            continue
        raise FormulaSyntaxError(f"unexpected {char!r}", line, column)
    out.append(Token("end", "", line, len(text) - line_start))
    return out
