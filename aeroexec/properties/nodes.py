"""The parsed form of a formula: a tree of frozen dataclasses.

Bounds are held in ticks (the parser turns seconds into ticks and refuses a bound that is
no multiple of one), so the semantics never see units. `unless` has no node of its own:
the parser writes it as RTAMT defines it (`always[0:b] a or a until[a:b] c`).
"""

from __future__ import annotations

from dataclasses import dataclass

#: Comparison operators as written (`!==` is RTAMT's "not equal").
COMPARISONS = ("<", "<=", ">", ">=", "==", "!==")
#: Arithmetic on two operands (`pow(a, b)` included).
ARITHMETIC = ("+", "-", "*", "/", "pow")
#: Functions of one operand.
FUNCTIONS = ("abs", "sqrt", "exp")
#: Boolean connectives on two operands.
CONNECTIVES = ("and", "or", "implies", "iff", "xor")
#: Operators on one operand that look at other samples (or none, for `not`).
UNARY = ("not", "rise", "fall", "prev", "next")
#: Temporal operators on one operand, bounded or not; future ones first.
TEMPORAL = ("always", "eventually", "historically", "once")
#: Temporal operators on two operands.
BETWEEN = ("until", "since")


@dataclass(frozen=True, slots=True)
class Signal:
    name: str


@dataclass(frozen=True, slots=True)
class Constant:
    value: float


@dataclass(frozen=True, slots=True)
class Compare:
    op: str  # one of COMPARISONS
    left: Node
    right: Node


@dataclass(frozen=True, slots=True)
class Arithmetic:
    op: str  # one of ARITHMETIC
    left: Node
    right: Node


@dataclass(frozen=True, slots=True)
class Function:
    op: str  # one of FUNCTIONS
    child: Node


@dataclass(frozen=True, slots=True)
class Connective:
    op: str  # one of CONNECTIVES
    left: Node
    right: Node


@dataclass(frozen=True, slots=True)
class Unary:
    op: str  # one of UNARY
    child: Node


@dataclass(frozen=True, slots=True)
class Window:
    """[begin, end] in ticks, 0 <= begin <= end."""

    begin: int
    end: int


@dataclass(frozen=True, slots=True)
class Temporal:
    op: str  # one of TEMPORAL
    child: Node
    window: Window | None  # None: unbounded (to the session's end or start)


@dataclass(frozen=True, slots=True)
class Between:
    op: str  # one of BETWEEN
    left: Node
    right: Node
    window: Window | None


Node = Signal | Constant | Compare | Arithmetic | Function | Connective | Unary | Temporal | Between


def children(node: Node) -> tuple[Node, ...]:
    if isinstance(node, Signal | Constant):
        return ()
    if isinstance(node, Function | Unary | Temporal):
        return (node.child,)
    return (node.left, node.right)
