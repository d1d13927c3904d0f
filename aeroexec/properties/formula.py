"""Formulas in RTAMT's signal temporal logic: checked, parsed and evaluated.

The language is RTAMT's (https://github.com/nickovic/rtamt); aeroexec parses it itself
(lexer.py, parser.py) and computes RTAMT's offline discrete-time semantics on arrays
(semantics.py). Around them (docs/properties.md#the-engine):

* **Nothing in a formula runs.** RTAMT's specification language also has declarations,
  and `from MODULE import TYPE` imports a Python module. A formula may hold only the
  tokens of an expression (operators, numbers, time units, known signal names); anything
  else is an error at its column, before the parser sees it. No text is evaluated.
* **Verdicts by Boolean semantics, robustness by the quantitative one.** With 0/1 signals
  the robustness of a satisfied comparison on its boundary (`landed >= 1` while landed)
  is 0, the same as a violated one's negation, so the sign of the robustness cannot say
  whether `fault_x >= 1 implies eventually[0:30](landed >= 1)` held. A second pass with
  each comparison mapped to +1/-1 decides it.
* **The first violating interval**: for `always(body)`, the first run of samples where the
  body is false; for any other formula, the whole session when it is false at 0.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from aeroexec.errors import Mark, PropertyError
from aeroexec.properties import nodes, semantics
from aeroexec.properties.lexer import FormulaSyntaxError, Token, tokenize
from aeroexec.properties.parser import parse
from aeroexec.properties.signals import PERIOD_NS, PERIOD_S


@dataclass(frozen=True, eq=False)
class Formula:
    """A parsed formula. `signals`: the signal names it reads, in order of appearance."""

    text: str
    signals: tuple[str, ...]
    mark: Mark
    #: The parsed formula (nodes.py), bounds in ticks.
    tree: nodes.Node
    #: Every use of a signal in the text, with its place in the property file.
    uses: tuple[tuple[str, Mark], ...] = ()
    #: The parameters it reads (property files' `parameters:`), in order of appearance.
    parameters: tuple[str, ...] = ()

    @cached_property
    def _sound(self) -> bool:
        """Whether the sign of the robustness decides the verdict (no iff, no xor)."""
        return not _has(
            self.tree, lambda n: isinstance(n, nodes.Connective) and n.op in ("iff", "xor")
        )

    @property
    def _always_body(self) -> nodes.Node | None:
        """The body of a top-level unbounded `always`, else None."""
        top = self.tree
        if isinstance(top, nodes.Temporal) and top.op == "always" and top.window is None:
            return top.child
        return None

    def horizon_s(self) -> float | None:
        """How far past a sample the body of a top-level `always` looks (None: without
        bound, or the formula is not an `always`): a violation at sample k is final once
        the session has reached k + horizon."""
        body = self._always_body
        if body is None:
            return None
        ticks = _future(body)
        return None if ticks is None else ticks * PERIOD_S

    def window_ticks(self) -> tuple[int, int] | None:
        """(past, future): how many ticks before and after a sample the body of a
        top-level `always` reads; None when either is unbounded (or the formula is no
        `always`): such a property can only be judged on the whole session."""
        body = self._always_body
        if body is None:
            return None
        future, past = _future(body), _past(body)
        if future is None or past is None:
            return None
        return past, future

    @cached_property
    def instant_body(self) -> Callable[[semantics.Sample], float] | None:
        """The body of a top-level `always` as a function of one sample's values, when it
        reads only the present sample (`semantics.instant`); else None."""
        body = self._always_body
        return None if body is None else semantics.instant(body)

    @cached_property
    def threshold(self) -> tuple[str, Callable[[float, float], bool], float] | None:
        """(signal, test, bound) when the body of a top-level `always` is one signal
        against a number (`always(distance_home <= 50)`, `always(0.05 <= battery)`, the
        commonest shape of a property that acts): at a sample it holds where
        `test(value, bound)`, the same verdict as `instant_body` (a NaN fails both). None
        for any other formula."""
        body = self._always_body
        if not isinstance(body, nodes.Compare):
            return None
        left, right = body.left, body.right
        if isinstance(left, nodes.Signal) and isinstance(right, nodes.Constant):
            return left.name, semantics.TESTS[body.op], float(right.value)
        if isinstance(left, nodes.Constant) and isinstance(right, nodes.Signal):
            # `c <= x` is `x >= c`, NaN included (both false).
            return right.name, semantics.TESTS[_MIRRORED[body.op]], float(left.value)
        return None

    def body_verdicts(self, columns: Mapping[str, Sequence[float]], length: int) -> np.ndarray:
        """The body of a top-level `always`, per sample: > 0 holds, < 0 violated."""
        body = self._always_body
        assert body is not None, "body_verdicts needs a formula always(body)"
        return semantics.series(body, self._arrays(columns), length, boolean=True)

    def robustness(self, columns: Mapping[str, Sequence[float]], length: int) -> np.ndarray:
        """The robustness of the formula at every sample."""
        return semantics.series(self.tree, self._arrays(columns), length)

    def verdicts(self, columns: Mapping[str, Sequence[float]], length: int) -> np.ndarray:
        """The truth of the formula at every sample: > 0 holds, < 0 violated."""
        return semantics.series(self.tree, self._arrays(columns), length, boolean=True)

    def evaluate(self, columns: Mapping[str, Sequence[float]], length: int) -> Outcome:
        """Evaluate on `length` samples of every signal in `signals`."""
        arrays = self._arrays(columns)
        rob = semantics.at_start(self.tree, arrays, length) if length else 0.0
        if rob > 0 and self._sound:
            # A positive robustness is a satisfaction (STL's soundness): the Boolean pass
            # would say the same.
            return Outcome(True, rob, None)
        body = self._always_body
        if body is not None:
            series = semantics.series(body, arrays, length, boolean=True)
        else:
            series = semantics.series(self.tree, arrays, length, boolean=True)[:1]
        violated = np.flatnonzero(series < 0)
        if len(violated) == 0:
            return Outcome(True, rob, None)
        first = int(violated[0])
        if len(series) == 1:
            return Outcome(False, rob, (0, length - 1))
        holds_after = np.flatnonzero(series[first:] >= 0)
        last = first + int(holds_after[0]) - 1 if len(holds_after) else len(series) - 1
        return Outcome(False, rob, (first, last))

    def _arrays(self, columns: Mapping[str, Sequence[float]]) -> dict[str, np.ndarray]:
        return {name: np.asarray(columns[name], dtype=float) for name in self.signals}


@dataclass(frozen=True, slots=True)
class Outcome:
    holds: bool
    #: The robustness at time 0 (how far from changing the verdict).
    robustness: float
    #: First and last sample of the first violating interval (None when it holds).
    interval: tuple[int, int] | None


def compile_formula(
    text: str,
    mark: Mark,
    known: Callable[[str], bool],
    parameters: Mapping[str, tuple[str, Mark]] | None = None,
) -> Formula:
    """Check and parse `text` (written at `mark`); `PropertyError` at the offending
    column for anything that is not an expression over known signals. `parameters`:
    names that stand for a number (its decimal text, and where it is set), wherever a
    number may stand: in a bound (`eventually[0:land_within_s]`) or a comparison. A
    value that does not fit there is an error where it is set."""
    #: (line, column) of each parameter in the text -> its name.
    standing: dict[tuple[int, int], str] = {}
    try:
        lexed = tokenize(text)
        names: list[str] = []
        uses: list[tuple[str, Mark]] = []
        read: list[str] = []
        for index, token in enumerate(lexed):
            if token.kind == "name" and parameters and token.text in parameters:
                value = parameters[token.text][0]
                lexed[index] = Token("number", value, token.line, token.column)
                standing[token.line, token.column] = token.text
                if token.text not in read:
                    read.append(token.text)
                continue
            if token.kind == "forbidden":
                raise FormulaSyntaxError(
                    f"'{token.text}' has no place in a formula (an expression over signals)",
                    token.line,
                    token.column,
                )
            if token.kind == "name":
                if not known(token.text):
                    raise FormulaSyntaxError(
                        f"unknown signal '{token.text}' (the signals are listed in "
                        "docs/properties.md)",
                        token.line,
                        token.column,
                    )
                if token.text not in names:
                    names.append(token.text)
                uses.append((token.text, _at(mark, token.line, token.column)))
        if len(lexed) == 1:
            raise PropertyError("empty formula", mark)
        tree = parse(text, PERIOD_NS, lexed)
    except FormulaSyntaxError as exc:
        place = _at(mark, exc.line, exc.column)
        name = standing.get((exc.line, exc.column))
        if name is not None and parameters is not None:
            value, where = parameters[name]
            raise PropertyError(
                f"parameter '{name}' = {value}: {exc.message} (in the formula at {place})", where
            ) from None
        raise PropertyError(exc.message, place) from None
    return Formula(text, tuple(names), mark, tree, tuple(uses), tuple(read))


_MIRRORED = {"<": ">", "<=": ">=", ">": "<", ">=": "<=", "==": "==", "!==": "!=="}


def _has(node: nodes.Node, test: Callable[[nodes.Node], bool]) -> bool:
    return test(node) or any(_has(child, test) for child in nodes.children(node))


def _future(node: nodes.Node) -> int | None:
    """The furthest a node looks ahead, in ticks (None: unbounded)."""
    own = 0
    if isinstance(node, nodes.Temporal | nodes.Between) and node.op in (
        "always",
        "eventually",
        "until",
    ):
        if node.window is None:
            return None
        own = node.window.end
    elif isinstance(node, nodes.Unary) and node.op == "next":
        own = 1
    return _deepest(node, _future, own)


def _past(node: nodes.Node) -> int | None:
    """The furthest a node looks back, in ticks (None: unbounded)."""
    own = 0
    if isinstance(node, nodes.Temporal | nodes.Between) and node.op in (
        "historically",
        "once",
        "since",
    ):
        if node.window is None:
            return None
        own = node.window.end
    elif isinstance(node, nodes.Unary) and node.op in ("prev", "rise", "fall"):
        own = 1
    return _deepest(node, _past, own)


def _deepest(node: nodes.Node, reach: Callable[[nodes.Node], int | None], own: int) -> int | None:
    deepest = 0
    for child in nodes.children(node):
        inner = reach(child)
        if inner is None:
            return None
        deepest = max(deepest, inner)
    return own + deepest


def _at(mark: Mark, line: int, column: int) -> Mark:
    """The place in the property file of (line, column) of the formula: exact for a
    formula on one line after its key; the formula's own start otherwise."""
    if mark.line <= 0:
        return mark
    if line <= 1:
        return Mark(mark.file, mark.line, mark.column + column)
    return Mark(mark.file, mark.line + line - 1, column + 1)
