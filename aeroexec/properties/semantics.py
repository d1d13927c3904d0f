"""RTAMT's discrete-time offline semantics, computed on numpy arrays.

RTAMT's own offline visitor works sample by sample on Python lists: about 0.1-0.6 s per
property on a one-hour recording (36,000 samples), 20 properties some 4 s, ten times the
cost of reading the channels (benchmarks/properties.py). This subclass of that visitor
computes the same operators on whole arrays (cumulative and sliding-window min/max), and
falls back to RTAMT's own code, unchanged, for the operators it does not vectorize
(timed until and since). `tests/test_properties_semantics.py` holds it to RTAMT's results
on every operator.

`boolean=True` maps each comparison to +1 (true) or -1 (false) instead of its robustness:
RTAMT's min/max operators then compute the Boolean semantics exactly (see formula.py).
"""

from __future__ import annotations

import operator
from typing import Any

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from rtamt.semantics.abstract_discrete_time_offline_interpreter import (
    discrete_time_offline_interpreter_factory,
)
from rtamt.semantics.stl.discrete_time.offline.ast_visitor import (
    StlDiscreteTimeOfflineAstVisitor,
)

_INF = float("inf")
_TESTS = {
    "<": operator.lt,
    "<=": operator.le,
    "==": operator.eq,
    "!=": operator.ne,
    ">": operator.gt,
    ">=": operator.ge,
}
Array = np.ndarray


class _ArrayVisitor(StlDiscreteTimeOfflineAstVisitor):  # type: ignore[misc]
    boolean = False

    def visit(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        # RTAMT dispatches through two chains of isinstance tests per node; an online
        # check of a few ticks spends most of its time there. The method named after the
        # node's class is the one those chains find (RTAMT's naming), so go there at once.
        method = getattr(self, "visit" + type(node).__name__, None)
        if method is None:
            return super().visit(node, *args, **kwargs)
        result = method(node, *args, **kwargs)
        self.ast.offline_results[node] = result
        return result

    # -- atoms --------------------------------------------------------------------------------
    def visitPredicate(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        left = self.visit(node.children[0], *args, **kwargs)
        right = self.visit(node.children[1], *args, **kwargs)
        op = str(node.operator)
        if self.boolean:
            return np.where(_TESTS[op](left, right), 1.0, -1.0)
        if op == "==":
            return -np.abs(left - right)
        if op == "!=":
            return np.abs(left - right)
        if op in ("<", "<="):
            return right - left
        return left - right

    def visitVariable(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return np.asarray(self.ast.var_object_dict[node.var], dtype=float)

    def visitConstant(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return np.full(args[0], float(node.val))

    # -- arithmetic ---------------------------------------------------------------------------
    def visitAbs(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return np.abs(self.visit(node.children[0], *args, **kwargs))

    def visitSqrt(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return np.sqrt(self.visit(node.children[0], *args, **kwargs))

    def visitExp(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return np.exp(self.visit(node.children[0], *args, **kwargs))

    def visitPow(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return np.power(*self._pair(node, args, kwargs))

    def visitAddition(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        left, right = self._pair(node, args, kwargs)
        return left + right

    def visitSubtraction(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        left, right = self._pair(node, args, kwargs)
        return left - right

    def visitMultiplication(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        left, right = self._pair(node, args, kwargs)
        return left * right

    def visitDivision(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        left, right = self._pair(node, args, kwargs)
        return left / right

    # -- Boolean ------------------------------------------------------------------------------
    def visitNot(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return -self.visit(node.children[0], *args, **kwargs)

    def visitAnd(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return np.minimum(*self._pair(node, args, kwargs))

    def visitOr(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return np.maximum(*self._pair(node, args, kwargs))

    def visitImplies(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        left, right = self._pair(node, args, kwargs)
        return np.maximum(-left, right)

    def visitIff(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        left, right = self._pair(node, args, kwargs)
        return -np.abs(left - right)

    def visitXor(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        left, right = self._pair(node, args, kwargs)
        return np.abs(left - right)

    # -- untimed temporal ---------------------------------------------------------------------
    def visitEventually(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        sample = self.visit(node.children[0], *args, **kwargs)
        return np.maximum.accumulate(sample[::-1])[::-1]

    def visitAlways(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        sample = self.visit(node.children[0], *args, **kwargs)
        return np.minimum.accumulate(sample[::-1])[::-1]

    def visitOnce(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return np.maximum.accumulate(self.visit(node.children[0], *args, **kwargs))

    def visitHistorically(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return np.minimum.accumulate(self.visit(node.children[0], *args, **kwargs))

    def visitUntil(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        left, right = (a.tolist() for a in self._pair(node, args, kwargs))
        out = [0.0] * len(left)
        following = -_INF
        for i in range(len(left) - 1, -1, -1):
            following = max(min(left[i], following), right[i])
            out[i] = following
        return np.asarray(out, dtype=float)

    def visitSince(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        left, right = (a.tolist() for a in self._pair(node, args, kwargs))
        out = [0.0] * len(left)
        before = -_INF
        for i in range(len(left)):
            before = max(min(left[i], before), right[i])
            out[i] = before
        return np.asarray(out, dtype=float)

    def visitRise(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        sample = self.visit(node.children[0], *args, **kwargs)
        return np.minimum(-_shift_right(sample, -_INF), sample)

    def visitFall(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        sample = self.visit(node.children[0], *args, **kwargs)
        return np.minimum(_shift_right(sample, _INF), -sample)

    def visitPrevious(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return _shift_right(self.visit(node.children[0], *args, **kwargs), _INF)

    def visitStrongPrevious(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return _shift_right(self.visit(node.children[0], *args, **kwargs), -_INF)

    def visitNext(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return _shift_left(self.visit(node.children[0], *args, **kwargs), _INF)

    def visitStrongNext(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return _shift_left(self.visit(node.children[0], *args, **kwargs), -_INF)

    # -- timed temporal: sliding windows --------------------------------------------------------
    def visitTimedEventually(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return self._ahead(node, args, kwargs, np.max, -_INF)

    def visitTimedAlways(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return self._ahead(node, args, kwargs, np.min, _INF)

    def visitTimedOnce(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return self._behind(node, args, kwargs, np.max, -_INF)

    def visitTimedHistorically(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return self._behind(node, args, kwargs, np.min, _INF)

    def visitTimedUntil(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return self._rtamt(StlDiscreteTimeOfflineAstVisitor.visitTimedUntil, node, args, kwargs)

    def visitTimedSince(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        return self._rtamt(StlDiscreteTimeOfflineAstVisitor.visitTimedSince, node, args, kwargs)

    # -- helpers ------------------------------------------------------------------------------
    def _pair(self, node: Any, args: Any, kwargs: Any) -> tuple[Array, Array]:
        return (
            self.visit(node.children[0], *args, **kwargs),
            self.visit(node.children[1], *args, **kwargs),
        )

    def _bounds(self, node: Any) -> tuple[int, int]:
        begin, end = self.time_unit_transformer(node)
        return int(begin), int(end)

    def _ahead(self, node: Any, args: Any, kwargs: Any, reduce: Any, pad: float) -> Array:
        """out[i] = reduce(x[i+begin .. i+end]), the samples past the end as `pad`."""
        sample = self.visit(node.children[0], *args, **kwargs)
        begin, end = self._bounds(node)
        padded = np.concatenate([sample, np.full(end + 1, pad)])
        windows = sliding_window_view(padded[begin:], end - begin + 1)
        return reduce(windows[: len(sample)], axis=1)

    def _behind(self, node: Any, args: Any, kwargs: Any, reduce: Any, pad: float) -> Array:
        """out[i] = reduce(x[i-end .. i-begin]), the samples before the start as `pad`."""
        sample = self.visit(node.children[0], *args, **kwargs)
        begin, end = self._bounds(node)
        padded = np.concatenate([np.full(end, pad), sample])
        windows = sliding_window_view(padded, end - begin + 1)
        return reduce(windows[: len(sample)], axis=1)

    def _rtamt(self, method: Any, node: Any, args: Any, kwargs: Any) -> Array:
        """RTAMT's own list-based code for `node`, its children given as lists."""
        array_visit = self.visit

        def as_list(child: Any, *a: Any, **k: Any) -> list[float]:
            del self.visit  # the grandchildren are computed on arrays again
            try:
                return list(array_visit(child, *a, **k).tolist())
            finally:
                self.visit = as_list

        self.visit = as_list  # RTAMT's methods reach the children through self.visit
        try:
            return np.asarray(method(self, node, *args, **kwargs), dtype=float)
        finally:
            del self.visit


class _BooleanVisitor(_ArrayVisitor):
    boolean = True

    # -|l - r| and |l - r| are 0 or 2 on +1/-1 values: the Boolean forms say it directly.
    def visitIff(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        left, right = self._pair(node, args, kwargs)
        return np.where((left > 0) == (right > 0), 1.0, -1.0)

    def visitXor(self, node: Any, *args: Any, **kwargs: Any) -> Array:
        left, right = self._pair(node, args, kwargs)
        return np.where((left > 0) != (right > 0), 1.0, -1.0)


def _shift_right(sample: Array, fill: float) -> Array:
    return np.concatenate([[fill], sample[:-1]]) if len(sample) else sample


def _shift_left(sample: Array, fill: float) -> Array:
    return np.concatenate([sample[1:], [fill]]) if len(sample) else sample


def interpreter(ast: Any, period_ms: int, *, boolean: bool) -> Any:
    """An RTAMT offline interpreter over `ast` that computes on arrays."""
    visitor = _BooleanVisitor if boolean else _ArrayVisitor
    made = discrete_time_offline_interpreter_factory(visitor)()
    made.set_ast(ast)
    made.set_sampling_period(period_ms, "ms", 0.1)
    return made


def run(made: Any, node: Any, columns: dict[str, Any], length: int) -> Array:
    """The series of `node` (and every node below it, kept in `ast.offline_results`)."""
    made.ast.var_object_dict.update(columns)
    made.ast.offline_results = {}
    return made.visit(node, length)
