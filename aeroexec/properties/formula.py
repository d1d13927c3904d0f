"""Formulas in RTAMT's signal temporal logic: checked, parsed and evaluated.

RTAMT (https://github.com/nickovic/rtamt) gives the language and its offline discrete-time
semantics. aeroexec adds three things around it (docs/properties.md#the-engine):

* **Nothing in a formula runs.** RTAMT's specification language also has declarations,
  and `from MODULE import TYPE` imports a Python module. A formula is lexed with RTAMT's
  own lexer first and may hold only the tokens of an expression (operators, numbers, time
  units, known signal names); anything else is an error at its column, before the parser
  sees it.
* **Verdicts by Boolean semantics, robustness by the quantitative one.** With 0/1 signals
  the robustness of a satisfied comparison on its boundary (`landed >= 1` while landed)
  is 0, the same as a violated one's negation, so the sign of the robustness cannot say
  whether `fault_x >= 1 implies eventually[0:30](landed >= 1)` held. A second pass with
  each comparison mapped to +1/-1 (RTAMT's own operators on top) decides it.
* **The first violating interval**: for `always(body)`, the first run of samples where the
  body is false; for any other formula, the whole session when it is false at 0.
"""

from __future__ import annotations

import contextlib
import io
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from aeroexec.errors import Mark, PropertyError
from aeroexec.properties import semantics
from aeroexec.properties.signals import PERIOD_NS, PERIOD_S

#: Tokens an expression may hold (RTAMT's lexer's symbolic names).
_ALLOWED_TOKENS = frozenset(
    {
        "MINUS",
        "PLUS",
        "TIMES",
        "DIVIDE",
        "LPAREN",
        "RPAREN",
        "LBRACK",
        "RBRACK",
        "COLON",
        "COMMA",
        "ABS",
        "SQRT",
        "EXP",
        "POW",
        "SEC",
        "MSEC",
        "USEC",
        "NSEC",
        "NotOperator",
        "OrOperator",
        "AndOperator",
        "IffOperator",
        "ImpliesOperator",
        "XorOperator",
        "RiseOperator",
        "FallOperator",
        "AlwaysOperator",
        "EventuallyOperator",
        "UntilOperator",
        "UnlessOperator",
        "HistoricallyOperator",
        "OnceOperator",
        "SinceOperator",
        "NextOperator",
        "PreviousOperator",
        "EqualOperator",
        "NotEqualOperator",
        "GreaterOrEqualOperator",
        "LesserOrEqualOperator",
        "GreaterOperator",
        "LesserOperator",
        "BooleanLiteral",
        "TRUE",
        "FALSE",
        "IntegerLiteral",
        "RealLiteral",
        "Identifier",
        "WHITESPACE",
        "LINE_TERMINATOR",
    }
)
_RTAMT_ERROR = re.compile(r"(\d+):(\d+):\s*(.*)", re.S)


@dataclass(frozen=True, slots=True)
class Token:
    kind: str
    text: str
    column: int  # 0-based, in the formula's text
    line: int  # 1-based, in the formula's text


@dataclass(frozen=True, eq=False)
class Formula:
    """A parsed formula. `signals`: the signal names it reads, in order of appearance."""

    text: str
    signals: tuple[str, ...]
    mark: Mark
    _spec: Any = field(repr=False)
    _boolean: Any = field(repr=False)
    #: Every use of a signal in the text, with its place in the property file.
    uses: tuple[tuple[str, Mark], ...] = ()

    @property
    def top(self) -> Any:
        return self._spec.ast.specs[0]

    @cached_property
    def _sound(self) -> bool:
        """Whether the sign of RTAMT's robustness decides the verdict (no iff, no xor)."""
        return not _has(self.top, ("Iff", "Xor"))

    @property
    def ast(self) -> Any:
        """RTAMT's parsed specification (for tests that hold our semantics to its)."""
        return self._spec.ast

    def horizon_s(self) -> float | None:
        """How far past a sample the body of a top-level `always` looks (None: without
        bound, or the formula is not an `always`): a violation at sample k is final once
        the session has reached k + horizon."""
        top = self.top
        if type(top).__name__ != "Always":
            return None
        return _future(top.children[0])

    def window_ticks(self) -> tuple[int, int] | None:
        """(past, future): how many ticks before and after a sample the body of a
        top-level `always` reads; None when either is unbounded (or the formula is no
        `always`): such a property can only be judged on the whole session."""
        top = self.top
        if type(top).__name__ != "Always":
            return None
        future = _future(top.children[0])
        past = _past(top.children[0])
        if future is None or past is None:
            return None
        return round(past / PERIOD_S), round(future / PERIOD_S)

    def body_verdicts(self, columns: Mapping[str, Sequence[float]], length: int) -> np.ndarray:
        """The body of a top-level `always`, per sample: > 0 holds, < 0 violated."""
        arrays = {name: np.asarray(columns[name], dtype=float) for name in self.signals}
        return semantics.run(self._boolean, self.top.children[0], arrays, length)

    def evaluate(self, columns: Mapping[str, Sequence[float]], length: int) -> Outcome:
        """Evaluate on `length` samples of every signal in `signals`."""
        arrays = {name: np.asarray(columns[name], dtype=float) for name in self.signals}
        top = self.top
        robustness = semantics.run(self._spec, top, arrays, length)
        rob = float(robustness[0]) if length else 0.0
        if rob > 0 and self._sound:
            # A positive robustness is a satisfaction (STL's soundness): the Boolean pass
            # would say the same.
            return Outcome(True, rob, None)
        verdicts = semantics.run(self._boolean, top, arrays, length)
        if type(top).__name__ == "Always":
            series = self._boolean.ast.offline_results[top.children[0]]
        else:
            series = verdicts[:1]
        violated = np.flatnonzero(series < 0)
        if len(violated) == 0:
            return Outcome(True, rob, None)
        first = int(violated[0])
        if len(series) == 1:
            return Outcome(False, rob, (0, length - 1))
        holds_after = np.flatnonzero(series[first:] >= 0)
        last = first + int(holds_after[0]) - 1 if len(holds_after) else len(series) - 1
        return Outcome(False, rob, (first, last))


@dataclass(frozen=True, slots=True)
class Outcome:
    holds: bool
    #: RTAMT's robustness at time 0 (how far from changing the verdict).
    robustness: float
    #: First and last sample of the first violating interval (None when it holds).
    interval: tuple[int, int] | None


def tokens(text: str) -> list[Token]:
    """`text` lexed by RTAMT's lexer; `PropertyError` text for what it cannot lex."""
    from antlr4 import InputStream
    from antlr4.error.ErrorListener import ErrorListener
    from rtamt.antlr.parser.stl.StlLexer import StlLexer

    problems: list[tuple[int, int, str]] = []

    class Collect(ErrorListener):  # type: ignore[misc]
        def syntaxError(self, recognizer, symbol, line, column, msg, e):
            problems.append((line, column, msg))

    with _quiet():
        lexer = StlLexer(InputStream(text))
    lexer.removeErrorListeners()
    lexer.addErrorListener(Collect())
    out = []
    for token in lexer.getAllTokens():
        kind = StlLexer.symbolicNames[token.type] if token.type > 0 else "<INVALID>"
        out.append(Token(kind, token.text, token.column, token.line))
    if problems:
        line, column, msg = problems[0]
        raise _LexError(line, column, msg.replace("token recognition error at", "unexpected"))
    return out


class _LexError(Exception):
    def __init__(self, line: int, column: int, message: str) -> None:
        super().__init__(message)
        self.line, self.column, self.message = line, column, message


def compile_formula(text: str, mark: Mark, known: Callable[[str], bool]) -> Formula:
    """Check and parse `text` (written at `mark`); `PropertyError` at the offending
    column for anything that is not an expression over known signals."""
    try:
        lexed = tokens(text)
    except _LexError as exc:
        raise PropertyError(exc.message, _at(mark, exc.line, exc.column)) from None
    names: list[str] = []
    uses: list[tuple[str, Mark]] = []
    for token in lexed:
        if token.kind not in _ALLOWED_TOKENS:
            raise PropertyError(
                f"'{token.text}' has no place in a formula (an expression over signals)",
                _at(mark, token.line, token.column),
            )
        if token.kind == "Identifier":
            if not known(token.text):
                raise PropertyError(
                    f"unknown signal '{token.text}' (the signals are listed in docs/properties.md)",
                    _at(mark, token.line, token.column),
                )
            if token.text not in names:
                names.append(token.text)
            uses.append((token.text, _at(mark, token.line, token.column)))
    if not any(t.kind not in ("WHITESPACE", "LINE_TERMINATOR") for t in lexed):
        raise PropertyError("empty formula", mark)
    spec, boolean = _parse(text, names, mark)
    formula = Formula(text, tuple(names), mark, spec, boolean, tuple(uses))
    try:  # bounds that are no multiple of the tick fail here, not in a check
        formula.evaluate({n: [0.0, 0.0] for n in names}, 2)
    except Exception as exc:
        raise PropertyError(_rtamt_message(exc), mark) from None
    return formula


def _parse(text: str, names: Sequence[str], mark: Mark) -> tuple[Any, Any]:
    import rtamt

    spec = rtamt.StlDiscreteTimeOfflineSpecification()
    for name in names:
        spec.declare_var(name, "float")
    spec.spec = text
    spec.set_sampling_period(PERIOD_NS // 1_000_000, "ms", 0.1)
    try:
        with _quiet():
            spec.parse()
    except Exception as exc:
        message = _rtamt_message(exc)
        found = _RTAMT_ERROR.match(message)
        if found:
            line, column, rest = int(found[1]), int(found[2]), found[3]
            raise PropertyError(_tidy(rest), _at(mark, line, column)) from None
        raise PropertyError(_tidy(message), mark) from None
    period_ms = PERIOD_NS // 1_000_000
    robustness = semantics.interpreter(spec.ast, period_ms, boolean=False)
    boolean = semantics.interpreter(spec.ast, period_ms, boolean=True)
    return robustness, boolean


def _future(node: Any) -> float | None:
    """The furthest a node looks ahead, in seconds (None: unbounded)."""
    kind = type(node).__name__
    if kind in ("Always", "Eventually", "Until", "Unless", "Next", "StrongNext"):
        if kind in ("Next", "StrongNext"):
            inner = _future(node.children[0])
            return None if inner is None else inner + PERIOD_S
        return None
    own = 0.0
    if kind.startswith("Timed") and kind[5:] in ("Always", "Eventually", "Until", "Unless"):
        own = float(node.end) * _unit_s(getattr(node, "end_unit", "") or "s")
    deepest = 0.0
    for child in node.children:
        inner = _future(child)
        if inner is None:
            return None
        deepest = max(deepest, inner)
    return own + deepest


def _has(node: Any, kinds: tuple[str, ...]) -> bool:
    return type(node).__name__ in kinds or any(_has(c, kinds) for c in node.children)


def _past(node: Any) -> float | None:
    """The furthest a node looks back, in seconds (None: unbounded)."""
    kind = type(node).__name__
    if kind in ("Historically", "Once", "Since"):
        return None
    own = 0.0
    if kind in ("TimedHistorically", "TimedOnce", "TimedSince"):
        own = float(node.end) * _unit_s(getattr(node, "end_unit", "") or "s")
    elif kind in ("Previous", "StrongPrevious", "Rise", "Fall"):
        own = PERIOD_S
    deepest = 0.0
    for child in node.children:
        inner = _past(child)
        if inner is None:
            return None
        deepest = max(deepest, inner)
    return own + deepest


def _unit_s(unit: str) -> float:
    return {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}.get(unit, 1.0)


def _at(mark: Mark, line: int, column: int) -> Mark:
    """The place in the property file of (line, column) of the formula: exact for a
    formula on one line after its key; the formula's own start otherwise."""
    if mark.line <= 0:
        return mark
    if line <= 1:
        return Mark(mark.file, mark.line, mark.column + column)
    return Mark(mark.file, mark.line + line - 1, column + 1)


def _rtamt_message(exc: BaseException) -> str:
    text = str(exc).strip() or type(exc).__name__
    return text.removeprefix("RTAMT Exception:").strip()


def _tidy(message: str) -> str:
    return " ".join(message.replace("Syntax ERROR,", "syntax error:").split())


@contextlib.contextmanager
def _quiet() -> Any:
    """RTAMT's generated lexer prints a version warning on standard output."""
    with contextlib.redirect_stdout(io.StringIO()):
        yield
