"""RTAMT's discrete-time offline semantics of STL, computed on numpy arrays.

The definitions are RTAMT 0.4.10's (its offline monitors, `rtamt.semantics.stl.
discrete_time.offline`), operator by operator: the robustness of `a <= b` is `b - a`,
`and`/`or` are min/max, `implies` is max(-a, b), `iff` and `xor` are -|a - b| and |a - b|,
`always[a:b] x` at sample i is the min of x over samples i+a..i+b (samples past the end
count as +inf, so a window cut off by the end is judged on what it holds), `once[a:b]`
the max over i-b..i-a (before the start: -inf), `a until[a:b] c` is the max over d in
a..b of min(c at i+d, a over i..i+d-1), `prev` and `next` read the neighbouring sample
(+inf past either end), `rise(x)` = min(not prev'(x), x) with -inf before the start.
tests/test_properties_semantics.py holds every operator to RTAMT's own monitors, sample
by sample, where RTAMT is installed.

What differs is only the cost: RTAMT works sample by sample on Python lists, and its
timed until/since are O(n·w²); here each operator is a few array operations (cumulative
and sliding-window min/max, and O(n·w) for timed until/since).

`boolean=True` maps each comparison to +1 (true) or -1 (false) instead of its robustness:
the min/max operators then compute the Boolean semantics exactly (see formula.py), and
`iff`/`xor` use their truth tables.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable, Mapping

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from aeroexec.properties import nodes

Array = np.ndarray
_INF = float("inf")
TESTS: dict[str, Callable[[Array | float, Array | float], Array]] = {
    "<": operator.lt,
    "<=": operator.le,
    "==": operator.eq,
    "!==": operator.ne,
    ">": operator.gt,
    ">=": operator.ge,
}


def series(
    node: nodes.Node, columns: Mapping[str, Array], length: int, *, boolean: bool = False
) -> Array:
    """The value of `node` at every one of `length` samples of `columns` (float arrays,
    one per signal the node reads): its robustness, or with `boolean` its truth as +1/-1."""
    with np.errstate(all="ignore"):  # sqrt(-1), x/0: nan and inf, as the formula says
        return _Evaluation(columns, length, boolean).value(node)


#: A whole-trace operator at the top, as its value at the first sample: a reduction of
#: its operand (the same float: min/max propagate NaN as their cumulative forms do).
_AT_START: dict[str, Callable[[Array], float]] = {
    "always": lambda inner: float(np.min(inner)),
    "eventually": lambda inner: float(np.max(inner)),
    "historically": lambda inner: float(inner[0]),
    "once": lambda inner: float(inner[0]),
}


def at_start(node: nodes.Node, columns: Mapping[str, Array], length: int) -> float:
    """`series(node, columns, length)[0]` (length > 0), without the series where only
    its first sample is read: a property's robustness is its value at the start, and
    most properties are `always(...)`, whose series is a reversed cumulative minimum
    (20 such cost more than reducing 20 arrays once)."""
    with np.errstate(all="ignore"):
        evaluation = _Evaluation(columns, length, False)
        if isinstance(node, nodes.Temporal) and node.window is None and node.op in _AT_START:
            return _AT_START[node.op](evaluation.value(node.child))
        return float(evaluation.value(node)[0])


class _Evaluation:
    def __init__(self, columns: Mapping[str, Array], length: int, boolean: bool) -> None:
        self.columns = columns
        self.length = length
        self.boolean = boolean

    def value(self, node: nodes.Node) -> Array:
        return _RULES[type(node)](self, node)

    # -- atoms ------------------------------------------------------------------------------------
    def signal(self, node: nodes.Signal) -> Array:
        return np.asarray(self.columns[node.name], dtype=float)

    def constant(self, node: nodes.Constant) -> Array:
        return np.full(self.length, node.value)

    def operands(
        self, node: nodes.Compare | nodes.Arithmetic
    ) -> tuple[Array | float, Array | float]:
        """Both sides; a number against a signal as that number, which numpy broadcasts
        (the same floats, without an array of it per use: most comparisons are one)."""
        left, right = node.left, node.right
        if isinstance(right, nodes.Constant) and not isinstance(left, nodes.Constant):
            return self.value(left), float(right.value)
        if isinstance(left, nodes.Constant) and not isinstance(right, nodes.Constant):
            return float(left.value), self.value(right)
        return self.value(left), self.value(right)

    def compare(self, node: nodes.Compare) -> Array:
        left, right = self.operands(node)
        if self.boolean:
            return np.where(TESTS[node.op](left, right), 1.0, -1.0)
        if node.op == "==":
            return -np.abs(left - right)
        if node.op == "!==":
            return np.abs(left - right)
        if node.op in ("<", "<="):
            return right - left
        return left - right

    # -- arithmetic -------------------------------------------------------------------------------
    def arithmetic(self, node: nodes.Arithmetic) -> Array:
        left, right = self.operands(node)
        if node.op == "+":
            return left + right
        if node.op == "-":
            return left - right
        if node.op == "*":
            return left * right
        if node.op == "/":
            return left / right
        return np.power(left, right)

    def function(self, node: nodes.Function) -> Array:
        inner = self.value(node.child)
        return {"abs": np.abs, "sqrt": np.sqrt, "exp": np.exp}[node.op](inner)

    # -- Boolean ----------------------------------------------------------------------------------
    def connective(self, node: nodes.Connective) -> Array:
        left, right = self.value(node.left), self.value(node.right)
        if node.op == "and":
            return np.minimum(left, right)
        if node.op == "or":
            return np.maximum(left, right)
        if node.op == "implies":
            return np.maximum(-left, right)
        if self.boolean:  # -|l - r| and |l - r| are 0 or 2 on +1/-1: say it directly
            same = (left > 0) == (right > 0)
            return np.where(same if node.op == "iff" else ~same, 1.0, -1.0)
        if node.op == "iff":
            return -np.abs(left - right)
        return np.abs(left - right)

    def unary(self, node: nodes.Unary) -> Array:
        inner = self.value(node.child)
        if node.op == "not":
            return -inner
        if node.op == "rise":
            return np.minimum(-_behind(inner, 1, -_INF), inner)
        if node.op == "fall":
            return np.minimum(_behind(inner, 1, _INF), -inner)
        if node.op == "prev":
            return _behind(inner, 1, _INF)
        return _ahead(inner, 1, _INF)  # next

    # -- temporal ---------------------------------------------------------------------------------
    def temporal(self, node: nodes.Temporal) -> Array:
        inner = self.value(node.child)
        op, window = node.op, node.window
        if window is None:
            if op == "always":
                return np.minimum.accumulate(inner[::-1])[::-1]
            if op == "eventually":
                return np.maximum.accumulate(inner[::-1])[::-1]
            if op == "historically":
                return np.minimum.accumulate(inner)
            return np.maximum.accumulate(inner)  # once
        if op == "always":
            return _window_ahead(inner, window, np.minimum, _INF)
        if op == "eventually":
            return _window_ahead(inner, window, np.maximum, -_INF)
        if op == "historically":
            return _window_behind(inner, window, np.minimum, _INF)
        return _window_behind(inner, window, np.maximum, -_INF)  # once

    def between(self, node: nodes.Between) -> Array:
        left, right = self.value(node.left), self.value(node.right)
        if node.window is not None:
            return _timed(left, right, node.window, future=node.op == "until")
        # Untimed: out[i] = max(right[i], min(left[i], out[i +/- 1])), a scan.
        lefts, rights = left.tolist(), right.tolist()
        out = [0.0] * len(lefts)
        carried = -_INF
        order = range(len(lefts) - 1, -1, -1) if node.op == "until" else range(len(lefts))
        for i in order:
            carried = max(min(lefts[i], carried), rights[i])
            out[i] = carried
        return np.asarray(out, dtype=float)


_RULES: dict[type, Callable[[_Evaluation, nodes.Node], Array]] = {
    nodes.Signal: _Evaluation.signal,
    nodes.Constant: _Evaluation.constant,
    nodes.Compare: _Evaluation.compare,
    nodes.Arithmetic: _Evaluation.arithmetic,
    nodes.Function: _Evaluation.function,
    nodes.Connective: _Evaluation.connective,
    nodes.Unary: _Evaluation.unary,
    nodes.Temporal: _Evaluation.temporal,
    nodes.Between: _Evaluation.between,
}  # type: ignore[dict-item]


def _timed(left: Array, right: Array, window: nodes.Window, *, future: bool) -> Array:
    """`left until[a:b] right` (future) or `left since[a:b] right`, in O(n·b):
    out[i] = max over d in a..b of min(right[i±d], left over the d samples from i towards
    it, i±d itself excluded); past either end, left is +inf and right -inf."""
    n = len(left)
    out = np.full(n, -_INF)
    held = np.full(n, _INF)  # min of left over the d samples from i towards i±d
    for d in range(min(window.end, n - 1) + 1):
        here = slice(0, n - d) if future else slice(d, n)
        there = slice(d, n) if future else slice(0, n - d)
        if d >= window.begin:
            np.maximum(out[here], np.minimum(held[here], right[there]), out=out[here])
        np.minimum(held[here], left[there], out=held[here])
    return out


def _window_ahead(sample: Array, window: nodes.Window, reduce: np.ufunc, pad: float) -> Array:
    """out[i] = reduce(x[i+begin .. i+end]), the samples past the end as `pad`."""
    padded = np.concatenate([sample, np.full(window.end + 1, pad)])
    return _sliding(padded[window.begin :], window.end - window.begin + 1, reduce, pad)[
        : len(sample)
    ]


def _window_behind(sample: Array, window: nodes.Window, reduce: np.ufunc, pad: float) -> Array:
    """out[i] = reduce(x[i-end .. i-begin]), the samples before the start as `pad`."""
    padded = np.concatenate([np.full(window.end, pad), sample])
    return _sliding(padded, window.end - window.begin + 1, reduce, pad)[: len(sample)]


#: Windows up to this many samples are reduced directly (a view of every window); longer
#: ones by van Herk and Gil-Werman's blocks, whose cost does not grow with the window.
_DIRECT = 8


def _sliding(x: Array, size: int, reduce: np.ufunc, pad: float) -> Array:
    """out[i] = reduce over x[i .. i+size-1], for every full window: min or max, exact
    (and NaN-propagating) either way, so both ways give the same values. Van Herk /
    Gil-Werman: cut x into blocks of `size`; a window is the suffix of one block and the
    prefix of the next, so out[i] = reduce(suffix[i], prefix[i+size-1]), in O(n)
    (a 30 s window over an hour's samples is 300 times less work than reducing each)."""
    count = len(x) - size + 1
    if count <= 0:
        return x[:0]
    if size <= _DIRECT:
        return reduce.reduce(sliding_window_view(x, size), axis=1)
    blocks = -(-len(x) // size)
    # The padding past the end lies in no full window's suffix nor prefix.
    padded = np.full(blocks * size, pad)
    padded[: len(x)] = x
    table = padded.reshape(blocks, size)
    prefix = reduce.accumulate(table, axis=1).ravel()
    suffix = reduce.accumulate(table[:, ::-1], axis=1)[:, ::-1].ravel()
    return reduce(suffix[:count], prefix[size - 1 : size - 1 + count])


# -- one sample at a time ------------------------------------------------------------------------
Sample = Mapping[str, float]


def instant(node: nodes.Node) -> Callable[[Sample], float] | None:
    """The Boolean semantics (`series(..., boolean=True)`) of a node that reads only the
    present sample, as a function of that sample's values (Python floats): what `series`
    gives at that sample (its sign always; its value too, but for the sign of a zero),
    without arrays, for a monitor that judges each tick as it ends (a few numpy calls
    cost more than the whole of it). None when the node looks at other samples or uses
    `exp` or `pow` (Python's math may round them differently from numpy). The function
    raises `ArithmeticError` or `ValueError` where numpy would make an inf or a nan out
    of an error (x/0, sqrt of a negative): then use `series`."""
    if isinstance(node, nodes.Signal):
        name = node.name
        return lambda values: values[name]
    if isinstance(node, nodes.Constant):
        constant = float(node.value)
        return lambda values: constant
    if isinstance(node, nodes.Function):
        child = instant(node.child)
        if child is None or node.op == "exp":
            return None
        if node.op == "abs":
            return lambda values: abs(child(values))
        return lambda values: math.sqrt(child(values))
    if isinstance(node, nodes.Unary):
        child = instant(node.child)
        if child is None or node.op != "not":
            return None
        return lambda values: -child(values)
    if not isinstance(node, nodes.Compare | nodes.Arithmetic | nodes.Connective):
        return None  # temporal
    left, right = instant(node.left), instant(node.right)
    if left is None or right is None:
        return None
    return _instant_pair(node, left, right)


def _instant_pair(
    node: nodes.Compare | nodes.Arithmetic | nodes.Connective,
    left: Callable[[Sample], float],
    right: Callable[[Sample], float],
) -> Callable[[Sample], float] | None:
    op = node.op
    if isinstance(node, nodes.Compare):
        test = TESTS[op]
        # A signal against a number, the common case (a geofence): one call, not three.
        if isinstance(node.left, nodes.Signal) and isinstance(node.right, nodes.Constant):
            name, bound = node.left.name, float(node.right.value)
            return lambda values: 1.0 if test(values[name], bound) else -1.0
        return lambda values: 1.0 if test(left(values), right(values)) else -1.0
    if isinstance(node, nodes.Arithmetic):
        if op == "pow":
            return None
        apply = {"+": operator.add, "-": operator.sub, "*": operator.mul, "/": operator.truediv}
        arithmetic = apply[op]
        return lambda values: arithmetic(left(values), right(values))
    if op == "and":
        return lambda values: _min(left(values), right(values))
    if op == "or":
        return lambda values: _max(left(values), right(values))
    if op == "implies":
        return lambda values: _max(-left(values), right(values))
    same = op == "iff"
    return lambda values: 1.0 if ((left(values) > 0) == (right(values) > 0)) == same else -1.0


def _min(a: float, b: float) -> float:
    """np.minimum: a NaN wins."""
    if a != a or b != b:
        return math.nan
    return a if a <= b else b


def _max(a: float, b: float) -> float:
    """np.maximum: a NaN wins."""
    if a != a or b != b:
        return math.nan
    return a if a >= b else b


def _behind(sample: Array, ticks: int, fill: float) -> Array:
    return np.concatenate([[fill] * ticks, sample[:-ticks]]) if len(sample) else sample


def _ahead(sample: Array, ticks: int, fill: float) -> Array:
    return np.concatenate([sample[ticks:], [fill] * ticks]) if len(sample) else sample
