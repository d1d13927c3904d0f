"""Beliefs: the small fact store behaviors and missions query (Aerostack's belief manager).

Syntax as in Aerostack: `predicate(arg, ...)`, nested tuples `(a, b)`, variables
`?Name`, the anonymous variable `?`; a query is a comma-separated conjunction solved
left to right with backtracking. `query('position(self, (?X, ?Y, ?Z))')` returns
`(True, {'X': 1.0, 'Y': 2.0, 'Z': 0.7})` or `(False, {})`.

Adding a belief replaces the one with the same predicate and first argument ("attribute
values are mutually exclusive"), except for multi-valued predicates such as
`visual_marker`, which accumulate.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, Union

from aeroexec.errors import AeroexecError


class BeliefSyntaxError(AeroexecError):
    """A belief expression or query does not parse."""


@dataclass(frozen=True, slots=True)
class Var:
    name: str  # "" for the anonymous variable `?`


@dataclass(frozen=True, slots=True)
class Compound:
    functor: str
    args: tuple[Term, ...]


Term = Union[str, int, float, Var, Compound, tuple]  # noqa: UP007 (recursive alias)

_TOKEN = re.compile(r"\s*(?:(\()|(\))|(,)|(\?[A-Za-z0-9_]*)|([A-Za-z0-9_\-+][A-Za-z0-9_.\-+]*))")
_NUMBER = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")
DEFAULT_MULTIVALUED = frozenset({"visual_marker", "object"})


def _tokens(text: str) -> list[str]:
    tokens: list[str] = []
    pos = 0
    text = text.rstrip()
    while pos < len(text):
        match = _TOKEN.match(text, pos)
        if not match or match.end() == pos:
            raise BeliefSyntaxError(f"cannot read {text!r} at character {pos + 1}")
        tokens.append(next(g for g in match.groups() if g is not None))
        pos = match.end()
    return tokens


def _atom(word: str) -> str | int | float:
    if _NUMBER.match(word):
        number = float(word)
        return int(number) if re.fullmatch(r"[-+]?\d+", word) else number
    return word


class _Parser:
    def __init__(self, text: str) -> None:
        self.text = text
        self.tokens = _tokens(text)
        self.pos = 0

    def peek(self) -> str | None:
        return self.tokens[self.pos] if self.pos < len(self.tokens) else None

    def take(self, expected: str | None = None) -> str:
        token = self.peek()
        if token is None or (expected is not None and token != expected):
            want = f"'{expected}'" if expected else "more"
            raise BeliefSyntaxError(f"in {self.text!r}: expected {want}, got {token or 'the end'}")
        self.pos += 1
        return token

    def sequence(self) -> tuple[Term, ...]:
        items = [self.term()]
        while self.peek() == ",":
            self.take(",")
            items.append(self.term())
        return tuple(items)

    def term(self) -> Term:
        token = self.take()
        if token == "(":
            items = self.sequence()
            self.take(")")
            return items
        if token in (")", ","):
            raise BeliefSyntaxError(f"in {self.text!r}: unexpected '{token}'")
        if token.startswith("?"):
            return Var(token[1:])
        if self.peek() == "(":
            self.take("(")
            args = self.sequence() if self.peek() != ")" else ()
            self.take(")")
            return Compound(token, args)
        return _atom(token)

    def finish(self) -> None:
        if self.peek() is not None:
            raise BeliefSyntaxError(f"in {self.text!r}: unexpected '{self.peek()}'")


def parse_query(text: str) -> tuple[Compound, ...]:
    parser = _Parser(text)
    terms = parser.sequence()
    parser.finish()
    for term in terms:
        if not isinstance(term, Compound):
            raise BeliefSyntaxError(f"in {text!r}: a belief is predicate(args), got {term!r}")
    return terms  # type: ignore[return-value]


def parse_belief(text: str) -> Compound:
    terms = parse_query(text)
    if len(terms) != 1:
        raise BeliefSyntaxError(f"{text!r}: one belief expected, got {len(terms)}")
    if not is_ground(terms[0]):
        raise BeliefSyntaxError(f"{text!r}: a belief cannot contain variables")
    return terms[0]


def is_ground(term: Term) -> bool:
    if isinstance(term, Var):
        return False
    if isinstance(term, Compound):
        return all(is_ground(a) for a in term.args)
    if isinstance(term, tuple):
        return all(is_ground(a) for a in term)
    return True


def render(term: Term) -> str:
    if isinstance(term, Compound):
        return f"{term.functor}({', '.join(render(a) for a in term.args)})"
    if isinstance(term, tuple):
        return "(" + ", ".join(render(a) for a in term) + ")"
    if isinstance(term, Var):
        return "?" + term.name
    if isinstance(term, float):
        return repr(term)
    return str(term)


def _value(term: Term) -> Any:
    """A bound value as the mission API returns it (tuples become lists)."""
    if isinstance(term, tuple):
        return [_value(t) for t in term]
    if isinstance(term, Compound):
        return render(term)
    return term


Bindings = dict[str, Term]


def _same_atom(a: Term, b: Term) -> bool:
    # 1 and 1.0 are the same number; True is never a number here.
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return float(a) == float(b)
    return type(a) is type(b) and a == b


def unify(pattern: Term, fact: Term, bindings: Bindings) -> Bindings | None:
    if isinstance(pattern, Var):
        if pattern.name == "":
            return bindings
        if pattern.name in bindings:
            return unify(bindings[pattern.name], fact, bindings)
        return {**bindings, pattern.name: fact}
    if isinstance(pattern, Compound):
        if not (
            isinstance(fact, Compound)
            and fact.functor == pattern.functor
            and len(fact.args) == len(pattern.args)
        ):
            return None
        return _unify_all(pattern.args, fact.args, bindings)
    if isinstance(pattern, tuple):
        if not isinstance(fact, tuple) or len(fact) != len(pattern):
            return None
        return _unify_all(pattern, fact, bindings)
    return bindings if _same_atom(pattern, fact) else None


def _unify_all(
    patterns: tuple[Term, ...], facts: tuple[Term, ...], bindings: Bindings
) -> Bindings | None:
    for p, f in zip(patterns, facts, strict=True):
        result = unify(p, f, bindings)
        if result is None:
            return None
        bindings = result
    return bindings


def _key(belief: Compound, multivalued: frozenset[str]) -> tuple[Any, ...]:
    """Beliefs with the same key replace each other."""
    if belief.functor in multivalued:
        return (belief.functor, render(belief))
    if len(belief.args) > 1:
        return (belief.functor, len(belief.args), render(belief.args[0]))
    return (belief.functor, len(belief.args))


class Beliefs:
    """An ordered fact store. `on_change(op, text)` is told of every add and remove;
    with `on_replace(old, new)`, an add that replaces a belief (same key: a vehicle's
    new position) is told there once instead of as a remove and an add."""

    def __init__(
        self,
        on_change: Callable[[str, str], None] | None = None,
        multivalued: frozenset[str] = DEFAULT_MULTIVALUED,
        on_replace: Callable[[str, str], None] | None = None,
    ) -> None:
        self._facts: dict[tuple[Any, ...], Compound] = {}
        self._on_change = on_change
        self._on_replace = on_replace
        self.multivalued = multivalued
        #: Counts changes (every add and remove): equal counts, equal contents.
        self.version = 0

    def __iter__(self) -> Iterator[Compound]:
        return iter(self._facts.values())

    def __len__(self) -> int:
        return len(self._facts)

    def texts(self) -> list[str]:
        return [render(f) for f in self._facts.values()]

    def add(self, belief: str | Compound) -> bool:
        """Add a ground belief; returns False when it was already there."""
        fact = parse_belief(belief) if isinstance(belief, str) else belief
        key = _key(fact, self.multivalued)
        old = self._facts.get(key)
        if old == fact:
            return False
        if old is not None:
            del self._facts[key]
            if self._on_replace is not None:
                self._facts[key] = fact
                self.version += 2  # a remove and an add, told as one
                self._on_replace(render(old), render(fact))
                return True
            self._notify("remove", old)
        self._facts[key] = fact
        self._notify("add", fact)
        return True

    def remove(self, belief: str | Compound) -> bool:
        """Remove every belief matching the (possibly non-ground) pattern."""
        pattern = parse_query(belief)[0] if isinstance(belief, str) else belief
        doomed = [k for k, f in self._facts.items() if unify(pattern, f, {}) is not None]
        for key in doomed:
            self._notify("remove", self._facts.pop(key))
        return bool(doomed)

    def set(self, belief: Compound) -> None:
        """Add or replace without complaint (the vehicle feeds beliefs this way)."""
        self.add(belief)

    def solve(self, query: str | tuple[Compound, ...]) -> Iterator[Bindings]:
        goals = parse_query(query) if isinstance(query, str) else query
        yield from self._solve(goals, 0, {})

    def _solve(self, goals: tuple[Compound, ...], i: int, bindings: Bindings) -> Iterator[Bindings]:
        if i == len(goals):
            yield bindings
            return
        for fact in list(self._facts.values()):
            result = unify(goals[i], fact, bindings)
            if result is not None:
                yield from self._solve(goals, i + 1, result)

    def query(self, query: str) -> tuple[bool, dict[str, Any]]:
        """`(True, {var: value})` for the first solution, `(False, {})` when none."""
        for bindings in self.solve(query):
            return True, {name: _value(value) for name, value in bindings.items()}
        return False, {}

    def holds(self, query: str) -> bool:
        return self.query(query)[0]

    def _notify(self, op: str, fact: Compound) -> None:
        self.version += 1
        if self._on_change is not None:
            self._on_change(op, render(fact))
