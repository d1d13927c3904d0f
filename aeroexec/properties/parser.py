"""Formulas in RTAMT's STL syntax, parsed into nodes.py's tree.

A precedence-climbing parser over lexer.py's tokens. The binding powers are those of
RTAMT's ANTLR grammar (0.4.10), so a formula means what it meant when RTAMT parsed it,
quirks included: each arithmetic operator has its own level (`*` 26, `/` 25, `+` 24,
`-` 23, so `a - b + c` is `a - (b + c)`), then comparisons (22), then the prefix operators
whose operand stops before any binary logic (`not` 21, `always` 20, `eventually` 19,
`historically` 18, `once` 17, `prev` 16, `next` 15), then `until` 12, `unless` 11,
`since` 10, `and` 9, `or` 8, `implies` 7, `iff` 6, `xor` 5. Binary operators group to the
left. A negative number is a literal (`-2`); there is no unary minus on expressions.

Where RTAMT's parser let nonsense through (`007` read as three formulas of which it kept
the first) or failed inside its own code (`unless` without bounds, a bound with a unit
on its start only), this parser says what is wrong or, for the last two, does what the
text says. tests/test_properties_semantics.py holds it to RTAMT on every operator and on
random formulas written without parentheses.
"""

from __future__ import annotations

from decimal import Decimal, InvalidOperation
from fractions import Fraction

from aeroexec.properties import nodes
from aeroexec.properties.lexer import FormulaSyntaxError, Token, tokenize

#: Binary operators: (binding power, canonical name). The right operand binds tighter.
_BINARY: dict[str, tuple[int, str]] = {
    "*": (26, "*"),
    "/": (25, "/"),
    "+": (24, "+"),
    "-": (23, "-"),
    **{op: (22, op) for op in nodes.COMPARISONS},
    "until": (12, "until"),
    "U": (12, "until"),
    "unless": (11, "unless"),
    "W": (11, "unless"),
    "since": (10, "since"),
    "S": (10, "since"),
    "and": (9, "and"),
    "or": (8, "or"),
    "implies": (7, "implies"),
    "iff": (6, "iff"),
    "xor": (5, "xor"),
}
#: Prefix operators: (binding power of their operand, canonical name).
_PREFIX: dict[str, tuple[int, str]] = {
    "not": (21, "not"),
    "always": (20, "always"),
    "G": (20, "always"),
    "eventually": (19, "eventually"),
    "F": (19, "eventually"),
    "historically": (18, "historically"),
    "H": (18, "historically"),
    "once": (17, "once"),
    "O": (17, "once"),
    "prev": (16, "prev"),
    "Y": (16, "prev"),
    "next": (15, "next"),
    "X": (15, "next"),
}
_UNIT_NS = {"s": 1_000_000_000, "ms": 1_000_000, "us": 1_000, "ns": 1}


def parse(text: str, period_ns: int, tokens: list[Token] | None = None) -> nodes.Node:
    """The tree of `text`, its bounds in ticks of `period_ns`; `FormulaSyntaxError` at the
    first token that does not fit. `tokens`: `text`'s, already cut (and a parameter's
    name replaced by its number)."""
    return _Parser(tokens if tokens is not None else tokenize(text), period_ns).formula()


class _Parser:
    def __init__(self, tokens: list[Token], period_ns: int) -> None:
        self.tokens = tokens
        self.at = 0
        self.period_ns = period_ns

    # -- the grammar -----------------------------------------------------------------------------
    def formula(self) -> nodes.Node:
        first = self.peek()
        if first.kind == "end":
            raise FormulaSyntaxError("empty formula", first.line, first.column)
        tree = self.expression(0)
        self.expect_end()
        return tree

    def expression(self, floor: int) -> nodes.Node:
        left = self.primary()
        while True:
            token = self.peek()
            if token.kind not in ("binary", "compare") or token.op not in _BINARY:
                return left
            power, op = _BINARY[token.op]
            if power < floor:
                return left
            self.advance()
            window = self.window() if op in ("until", "unless", "since") else None
            right = self.expression(power + 1)
            left = _combine(op, left, right, window)

    def primary(self) -> nodes.Node:
        token = self.advance()
        if token.text == "(":
            inner = self.expression(0)
            self.expect(")")
            return inner
        if token.kind == "function":
            self.expect("(")
            first = self.expression(0)
            if token.text == "pow":
                self.expect(",")
                second = self.expression(0)
                self.expect(")")
                return nodes.Arithmetic("pow", first, second)
            self.expect(")")
            return nodes.Function(token.text, first)
        if token.kind == "edge":
            self.expect("(")
            inner = self.expression(0)
            self.expect(")")
            return nodes.Unary(token.text, inner)
        if token.kind == "prefix":
            power, op = _PREFIX[token.op]
            if op in nodes.TEMPORAL:
                window = self.window()
                return nodes.Temporal(op, self.expression(power), window)
            return nodes.Unary(op, self.expression(power))
        if token.kind == "name":
            return nodes.Signal(token.text)
        if token.kind == "number" or token.text == "-":
            return nodes.Constant(float(self.number(token)))
        raise self.unexpected(token)

    def window(self) -> nodes.Window | None:
        if self.peek().text != "[":
            return None
        self.advance()
        begin, begin_unit, begin_at = self.bound()
        separator = self.advance()
        if separator.text not in (":", ","):
            raise self.unexpected(separator, "':'")
        end, end_unit, end_at = self.bound()
        self.expect("]")
        # RTAMT: a bound without a unit takes the other's, both none: seconds.
        begin_unit = begin_unit or end_unit or "s"
        end_unit = end_unit or begin_unit
        first = self.ticks(begin, begin_unit, begin_at)
        last = self.ticks(end, end_unit, end_at)
        if first > last:
            raise FormulaSyntaxError(
                "the interval's start is after its end", begin_at.line, begin_at.column
            )
        return nodes.Window(first, last)

    def bound(self) -> tuple[Fraction, str, Token]:
        token = self.advance()
        if token.kind not in ("number",) and token.text != "-":
            raise FormulaSyntaxError(
                "syntax error: a bound is a number of seconds, or with a unit (s, ms, us, ns)",
                token.line,
                token.column,
            )
        value = self.number(token)
        unit = self.advance().text if self.peek().kind == "unit" else ""
        if value < 0:
            raise FormulaSyntaxError("a bound cannot be negative", token.line, token.column)
        return value, unit, token

    def ticks(self, value: Fraction, unit: str, token: Token) -> int:
        ticks = value * _UNIT_NS[unit] / self.period_ns
        if ticks.denominator != 1:
            seconds = Fraction(self.period_ns, 1_000_000_000)
            raise FormulaSyntaxError(
                "the operator bound must be a multiple of the sampling period "
                f"({float(seconds):g} s)",
                token.line,
                token.column,
            )
        return int(ticks)

    def number(self, token: Token) -> Fraction:
        """The literal starting at `token` (already consumed): a number, maybe after a
        minus, as an exact fraction (bounds are compared with the tick exactly)."""
        negative = token.text == "-"
        if negative:
            token = self.advance()
            if token.kind != "number":
                raise self.unexpected(token, "a number")
        text = token.text.replace("_", "")
        if text[:2].lower() in ("0x", "0b"):
            raise FormulaSyntaxError(
                f"'{token.text}': numbers are decimal in a formula", token.line, token.column
            )
        try:
            value = Fraction(Decimal(text))
        except (InvalidOperation, ValueError):  # the lexer's numbers all convert
            raise self.unexpected(token) from None
        return -value if negative else value

    # -- tokens ----------------------------------------------------------------------------------
    def peek(self) -> Token:
        return self.tokens[self.at]

    def advance(self) -> Token:
        token = self.tokens[self.at]
        if token.kind != "end":
            self.at += 1
        return token

    def expect(self, text: str) -> None:
        token = self.advance()
        if token.text != text or token.kind == "end":
            raise self.unexpected(token, f"'{text}'")

    def expect_end(self) -> None:
        token = self.peek()
        if token.kind != "end":
            raise self.unexpected(token, "the end of the formula")

    @staticmethod
    def unexpected(token: Token, wanted: str = "") -> FormulaSyntaxError:
        found = "the end of the formula" if token.kind == "end" else f"'{token.text}'"
        expected = f"expected {wanted}, found {found}" if wanted else f"unexpected {found}"
        return FormulaSyntaxError(f"syntax error: {expected}", token.line, token.column)


def _combine(
    op: str, left: nodes.Node, right: nodes.Node, window: nodes.Window | None
) -> nodes.Node:
    if op in nodes.COMPARISONS:
        return nodes.Compare(op, left, right)
    if op in nodes.ARITHMETIC:
        return nodes.Arithmetic(op, left, right)
    if op in nodes.CONNECTIVES:
        return nodes.Connective(op, left, right)
    if op == "unless":
        # RTAMT's definition: a holds throughout [0, b], or until c within [a, b].
        always = nodes.Window(0, window.end) if window else None
        return nodes.Connective(
            "or",
            nodes.Temporal("always", left, always),
            nodes.Between("until", left, right, window),
        )
    return nodes.Between(op, left, right, window)
