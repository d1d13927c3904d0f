"""Fold a mission script into the sequence of mission API calls it makes, without running it.

The script's AST is interpreted abstractly, from its entry point (`runMission()`, or
`run_mission()` / `main()`, after the module's top level, as `aeroexec run` does):

* constants are folded: a behavior name in a variable (`name = 'TAKE_OFF'`), string
  arithmetic, a name looked up in a dict or list that nothing mutates (`NAMES['up']`,
  `NAMES.get('up')`), a loop over a literal list of names or a constant `range(n)`,
  and a `while` on a counter the body changes (`n < 3`, `n += 1`), unrolled, `break`
  and `continue` included, helper functions called with constant
  arguments (inlined, also for their return value), aliases of the API (`go =
  api.executeBehavior`, `from executive_engine_api import executeBehavior as go`);
* `try`/`except`/`else`/`finally` and `with` keep Python's semantics (`Try`): a
  `finally` runs on every way out of its body (normal end, `return`, `break`,
  `continue`, an exception), a `with` on a `@contextmanager` helper of the script runs
  the helper's code before and after its `yield` around the body;
* what depends on the run (a belief, a behavior's result, a loop over data) stays
  unknown: an `if` on it keeps both branches, a loop on it becomes a `Loop` node.

The result is a `Flow`: mission calls (`CallNode`, each a `MissionCall` with folded
arguments and the helper calls that lead to it), `Branch`, `Loop`, `Unrolled` (a
constant loop whose body jumps), `Try`, `Inline` (a helper's body) and the jumps
`return`, `break`, `continue`, `raise`. `aeroexec.verifier.mission_run` runs it
against the executive; the per-call rules (AX70x) check every `MissionCall` it
contains. A call whose behavior name cannot be folded is "not checked" (AX708 names
its line).

Nesting is bounded (blocks, inlined helpers, expressions), so a pathological script
cannot exhaust Python's recursion limit here: what lies deeper is left unfolded and its
calls are checked as written.
"""

from __future__ import annotations

import ast
import operator
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

from aeroexec.errors import Mark

#: Mission API functions -> what they do.
MISSION_CALLS = {
    "execute_behavior": "execute",
    "executeBehavior": "execute",
    "activate_behavior": "activate",
    "activateBehavior": "activate",
    "inhibit_behavior": "inhibit",
    "inhibitBehavior": "inhibit",
}
#: What `aeroexec run` calls after the module's top level (mission/script.py).
ENTRY_POINTS = ("runMission", "run_mission", "main")
API_MODULE = "executive_engine_api"
#: `__name__` while `aeroexec run` executes a mission (mission/script.py).
RUN_NAME = "__aeroexec_mission__"

MAX_NESTING = 60  # blocks and inlined helpers, together
MAX_INLINE = 8  # helper calls inside helper calls
MAX_EXPRESSION = 40  # depth of an expression the folder evaluates
MAX_UNROLL = 64  # items of a literal sequence a `for` is unrolled over
#: Iterations unrolled in one mission, all loops together: nested constant loops
#: (`range(64)` in `range(64)` in ...) stay loops beyond it (AX715 says so).
MAX_UNROLLED = 1_000
#: Methods that read a list or dict without changing it; any other method called on a
#: name makes the folder forget what the name holds.
_READING_METHODS = frozenset({"get", "keys", "values", "items", "copy", "index", "count"})


class _Unknown:
    """A value the verifier cannot know without running the mission."""

    def __repr__(self) -> str:
        return "<not a literal>"


UNKNOWN: Any = _Unknown()


@dataclass(frozen=True, slots=True)
class _Api:
    kind: str  # execute | activate | inhibit
    function: str


@dataclass(frozen=True, slots=True)
class _Function:
    node: ast.FunctionDef


@dataclass(frozen=True, slots=True)
class _Module:
    name: str


@dataclass(frozen=True, slots=True)
class _DictGet:
    mapping: dict[Any, Any]


@dataclass(frozen=True, slots=True)
class _StringMethod:
    text: str
    method: str


# -- what the folder produces -----------------------------------------------------------
@dataclass(frozen=True, slots=True)
class CallArgument:
    name: str
    value: Any  # a literal, UNKNOWN, or a list that may contain UNKNOWN
    mark: Mark


@dataclass(frozen=True, slots=True)
class MissionCall:
    kind: str  # "execute" | "activate" | "inhibit"
    function: str  # as written: executeBehavior, inhibit_behavior...
    behavior: str | None  # None when the name cannot be folded to a string
    arguments: tuple[CallArgument, ...]
    positional: tuple[Mark, ...]  # extra positional arguments after the name
    mark: Mark
    name_mark: Mark
    #: The helper calls that lead here, outermost first: (helper name, call site).
    via: tuple[tuple[str, Mark], ...] = ()

    @property
    def shown(self) -> str:
        return f"{self.function}('{self.behavior}')"


@dataclass(frozen=True, slots=True)
class CallNode:
    call: MissionCall


@dataclass(frozen=True, slots=True)
class Branch:
    mark: Mark
    arms: tuple[tuple[str, Flow], ...]  # ("if", flow), ("else", flow)


@dataclass(frozen=True, slots=True)
class Loop:
    mark: Mark
    body: Flow
    may_skip: bool  # the body may run zero times
    ends_by_condition: bool  # False for `while True:` (only break/return leave it)


@dataclass(frozen=True, slots=True)
class Unrolled:
    """A `for` over a constant sequence whose body may `break`/`continue`: one flow
    per item, in order; `orelse` runs when no iteration breaks."""

    mark: Mark
    iterations: tuple[Flow, ...]
    orelse: Flow


@dataclass(frozen=True, slots=True)
class Handler:
    mark: Mark
    catches_all: bool  # bare `except:`, `except Exception`, `except BaseException`
    body: Flow


@dataclass(frozen=True, slots=True)
class Try:
    """`try`/`except`/`else`/`finally` (and `with`): `finalbody` runs on every way
    out of `body`, handlers and `orelse`; a jump inside `finalbody` replaces the one
    in flight, as in Python."""

    mark: Mark
    body: Flow
    handlers: tuple[Handler, ...]
    orelse: Flow
    finalbody: Flow


@dataclass(frozen=True, slots=True)
class Inline:
    name: str
    mark: Mark
    body: Flow
    #: A `@contextmanager` helper around a `with` body: a `return`, `break` or
    #: `continue` of the body leaves the caller (after the helper's `finally`), not
    #: just the helper.
    passthrough: bool = False


@dataclass(frozen=True, slots=True)
class Jump:
    kind: str  # "return" | "break" | "continue" | "raise"
    mark: Mark


Node = CallNode | Branch | Loop | Unrolled | Try | Inline | Jump
Flow = tuple[Node, ...]


@dataclass(frozen=True)
class FoldedMission:
    """The mission as the verifier understands it."""

    flow: Flow
    #: The entry point found (None: the script defines none).
    entry: str | None
    #: Every mission call the folder reached, in order, with folded arguments.
    calls: tuple[MissionCall, ...]
    #: API call sites whose behavior name could not be folded (by place).
    unchecked: tuple[Mark, ...] = field(default=())
    #: Bounds the folding reached (constant loops left as loops), for AX715.
    bounds: tuple[str, ...] = field(default=())


# -- folding --------------------------------------------------------------------------------
_BINARY: dict[type[ast.operator], Callable[[Any, Any], Any]] = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.FloorDiv: operator.floordiv,
    ast.Mod: operator.mod,
}
_COMPARE: dict[type[ast.cmpop], Callable[[Any, Any], Any]] = {
    ast.Eq: operator.eq,
    ast.NotEq: operator.ne,
    ast.Lt: operator.lt,
    ast.LtE: operator.le,
    ast.Gt: operator.gt,
    ast.GtE: operator.ge,
    ast.In: lambda a, b: a in b,
    ast.NotIn: lambda a, b: a not in b,
    ast.Is: operator.is_,
    ast.IsNot: operator.is_not,
}
_STRING_METHODS = {"upper", "lower", "strip", "capitalize", "title"}
_CONSTANT_TYPES = (str, int, float, bool, type(None))


def is_known(value: Any) -> bool:
    """A plain constant, or a tuple/list of them all known."""
    if isinstance(value, (list, tuple)):
        return all(is_known(v) for v in value)
    if isinstance(value, dict):
        return all(is_known(k) and is_known(v) for k, v in value.items())
    return isinstance(value, _CONSTANT_TYPES)


def _constant_result(function: Callable[..., Any], *args: Any) -> Any:
    repeats = any(isinstance(a, int) and not isinstance(a, bool) and abs(a) > 10_000 for a in args)
    if (
        function is operator.mul
        and repeats
        and any(isinstance(a, (str, list, tuple)) for a in args)
    ):
        return UNKNOWN  # `'x' * 10**9` must never be built, and no behavior name needs it
    try:
        result = function(*args)
    except Exception:  # a TypeError of mixed types, a ZeroDivisionError...
        return UNKNOWN
    if isinstance(result, (str, list, tuple)) and len(result) > 10_000:
        return UNKNOWN
    return result if is_known(result) else UNKNOWN


_BUILTINS = frozenset(
    {"range", "len", "list", "tuple", "reversed", "sorted", "enumerate", "str", "min", "max"}
)


def _builtin(name: str, args: list[Any]) -> Any:
    """A pure builtin on known arguments; UNKNOWN when it fails or grows too large."""
    if name == "range":
        if not (1 <= len(args) <= 3) or not all(
            isinstance(a, int) and not isinstance(a, bool) for a in args
        ):
            return UNKNOWN
        try:
            numbers = range(*args)
        except ValueError:  # a zero step
            return UNKNOWN
        return list(numbers) if len(numbers) <= 10_000 else UNKNOWN
    if name not in ("min", "max"):
        if len(args) != 1:
            return UNKNOWN
        if name != "str" and not isinstance(args[0], (str, list, tuple, dict)):
            return UNKNOWN
    elif not args:
        return UNKNOWN
    functions: dict[str, Callable[..., Any]] = {
        "len": len,
        "list": list,
        "tuple": tuple,
        "reversed": lambda x: list(reversed(list(x))),
        "sorted": sorted,
        "enumerate": lambda x: [tuple(p) for p in enumerate(x)],
        "str": str,
        "min": min,
        "max": max,
    }
    return _constant_result(functions[name], *args)


def _merge_into(env: dict[str, Any], other: dict[str, Any]) -> None:
    """After two ways through the script meet: a name keeps its value only when both
    agree on it."""
    for name in set(env) | set(other):
        a, b = env.get(name, UNKNOWN), other.get(name, UNKNOWN)
        env[name] = a if a is b or (is_known(a) and is_known(b) and a == b) else UNKNOWN


def _jumps_out(statements: Sequence[ast.stmt]) -> bool:
    """Whether a `return`, `break` or `continue` may leave these statements (nested
    functions and classes excluded)."""
    stack: list[ast.AST] = list(statements)
    while stack:
        node = stack.pop()
        if isinstance(node, (ast.Return, ast.Break, ast.Continue)):
            return True
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Lambda)):
            continue
        stack.extend(ast.iter_child_nodes(node))
    return False


def _catches_all(kind: ast.expr | None) -> bool:
    return kind is None or (
        isinstance(kind, ast.Name) and kind.id in ("Exception", "BaseException")
    )


def _mutated_names(tree: ast.AST) -> set[str]:
    """Names whose contents the script may change in place anywhere: `d[k] = v`, `del
    d[k]`, `names.append(x)` (any method but those that only read), `global name`."""
    names: set[str] = set()
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Subscript)
            and isinstance(node.ctx, (ast.Store, ast.Del))
            and isinstance(node.value, ast.Name)
        ):
            names.add(node.value.id)
        elif (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and isinstance(node.func.value, ast.Name)
            and node.func.attr not in _READING_METHODS
        ):
            names.add(node.func.value.id)
        elif isinstance(node, (ast.Global, ast.Nonlocal)):
            names.update(node.names)
    return names


class Folder:
    def __init__(self, file: str, lines: Sequence[str]) -> None:
        self.file = file
        self.lines = lines
        self.calls: list[MissionCall] = []
        self.unchecked: dict[tuple[int, int], Mark] = {}
        self.functions_on_stack: list[str] = []
        self.nesting = 0
        #: Values `return` gave in the helper being inlined (innermost last).
        self.returns: list[list[Any]] = []
        #: The helper calls being inlined, outermost first: (helper, call site).
        self.via: list[tuple[str, Mark]] = []
        #: Names whose list or dict something may change in place (`d[k] = v`,
        #: `names.append(...)`): the folder never trusts their contents.
        self.mutated: set[str] = set()
        #: `with` bodies waiting for the `yield` of their `@contextmanager` helper:
        #: (statements, the caller's environment, how many helpers are inlined while
        #: the helper's own body runs), innermost last.
        #: Iterations unrolled so far, and the loops left as loops for the budget.
        self.unrolled = 0
        self.bounds: list[str] = []
        self.with_bodies: list[
            tuple[Sequence[ast.stmt], dict[str, Any], int, list[tuple[str, Mark]]]
        ] = []

    def mark(self, node: ast.AST) -> Mark:
        """1-based line and character column (ast counts UTF-8 bytes)."""
        line = getattr(node, "lineno", 0)
        offset = getattr(node, "col_offset", 0)
        if 0 < line <= len(self.lines):
            prefix = self.lines[line - 1].encode("utf-8")[:offset]
            offset = len(prefix.decode("utf-8", errors="replace"))
        return Mark(self.file, line, offset + 1)

    # -- the whole script ------------------------------------------------------------------
    def fold(self, tree: ast.Module) -> FoldedMission:
        self.mutated = _mutated_names(tree)
        env: dict[str, Any] = {"__name__": RUN_NAME}
        flow = list(self.block(tree.body, env))
        entry = next((name for name in ENTRY_POINTS if isinstance(env.get(name), _Function)), None)
        if entry is not None:
            function: _Function = env[entry]
            flow.append(Inline(entry, self.mark(function.node), self.inline(function, [], {}, env)))
        return FoldedMission(
            tuple(flow),
            entry,
            tuple(self.calls),
            tuple(sorted(self.unchecked.values(), key=lambda m: (m.line, m.column))),
            tuple(dict.fromkeys(self.bounds)),
        )

    # -- statements ----------------------------------------------------------------------
    def block(self, statements: Sequence[ast.stmt], env: dict[str, Any]) -> Flow:
        if self.nesting >= MAX_NESTING:
            return ()
        self.nesting += 1
        try:
            out: list[Node] = []
            for statement in statements:
                out.extend(self.statement(statement, env))
                if out and isinstance(out[-1], Jump):
                    break  # what follows a return/break/continue never runs
            return tuple(out)
        finally:
            self.nesting -= 1

    def statement(self, node: ast.stmt, env: dict[str, Any]) -> Iterator[Node]:
        if (
            isinstance(node, ast.Expr)
            and isinstance(node.value, ast.Yield)
            and self.with_bodies
            and self.with_bodies[-1][2] == len(self.functions_on_stack)
        ):
            # The `yield` of a @contextmanager helper (its own, not one of a generator
            # it calls): the `with` body runs here, in its caller's environment.
            body, caller_env, _, caller_via = self.with_bodies.pop()
            inside, self.via = self.via, caller_via  # the body's calls are the caller's
            try:
                yield from self.block(body, caller_env)
            finally:
                self.via = inside
        elif isinstance(node, ast.Expr):
            yield from self.expression_calls(node.value, env)
        elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
            yield from self.assignment(node, env)
        elif isinstance(node, ast.If):
            yield from self.if_statement(node, env)
        elif isinstance(node, (ast.For, ast.AsyncFor)):
            yield from self.for_statement(node, env)
        elif isinstance(node, ast.While):
            yield from self.while_statement(node, env)
        elif isinstance(node, ast.Return):
            if node.value is not None:
                nodes, value = self.evaluate_with_calls(node.value, env)
                yield from nodes
                if self.returns:
                    self.returns[-1].append(value)
            yield Jump("return", self.mark(node))
        elif isinstance(node, ast.Raise):
            yield Jump("raise", self.mark(node))
        elif isinstance(node, ast.Break):
            yield Jump("break", self.mark(node))
        elif isinstance(node, ast.Continue):
            yield Jump("continue", self.mark(node))
        elif isinstance(node, ast.FunctionDef):
            env[node.name] = _Function(node)
        elif isinstance(node, (ast.AsyncFunctionDef, ast.ClassDef)):
            env[node.name] = UNKNOWN
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            self.imports(node, env)
        elif isinstance(node, (ast.With, ast.AsyncWith)):
            yield from self.with_statement(node.items, node.body, env, self.mark(node))
        elif isinstance(node, ast.Try) or type(node).__name__ == "TryStar":
            yield self.try_statement(node, env)  # type: ignore[arg-type]
        elif isinstance(node, ast.Match):
            arms = []
            for case in node.cases:
                arm_env = dict(env)
                arms.append((f"case line {case.pattern.lineno}", self.block(case.body, arm_env)))
            arms.append(("no case", ()))
            yield Branch(self.mark(node), tuple(arms))
            self.forget_assigned(node, env)
        else:  # pass, global, delete, assert...: no mission call, no constant
            for child in ast.iter_child_nodes(node):
                if isinstance(child, ast.expr):
                    yield from self.expression_calls(child, env)

    def with_statement(
        self,
        items: Sequence[ast.withitem],
        body: Sequence[ast.stmt],
        env: dict[str, Any],
        mark: Mark,
    ) -> Iterator[Node]:
        """`with a, b: body` is `with a: with b: body`. A `@contextmanager` helper of the
        script is inlined with the body at its `yield` (its `finally` runs on the way
        out); any other context manager is code the folder does not know: its exit
        makes no mission call, the body runs as written."""
        if not items:
            yield from self.block(body, env)
            return
        item, rest = items[0], items[1:]
        manager = self.context_manager(item.context_expr, env)
        if manager is not None:
            function, call = manager
            if item.optional_vars is not None:  # what the helper yields: not folded
                self.bind(item.optional_vars, UNKNOWN, env)
            args = [self.evaluate(a, env, [], 0) for a in call.args]
            keywords = {k.arg: self.evaluate(k.value, env, [], 0) for k in call.keywords}
            inner = [ast.With(items=list(rest), body=list(body))] if rest else list(body)
            for statement in inner:
                ast.copy_location(statement, item.context_expr)
            level = len(self.functions_on_stack) + 1
            self.with_bodies.append((inner, env, level, list(self.via)))
            depth = len(self.with_bodies)
            self.via.append((function.node.name, self.mark(call)))
            try:
                flow = self.inline(function, args, keywords, env)
            finally:
                self.via.pop()
            if len(self.with_bodies) >= depth:  # the helper never reached its yield
                del self.with_bodies[depth - 1 :]
            yield Inline(function.node.name, self.mark(call), flow, passthrough=True)
            return
        yield from self.expression_calls(item.context_expr, env)
        if item.optional_vars is not None:
            self.bind(item.optional_vars, UNKNOWN, env)
        inner_flow = tuple(self.with_statement(rest, body, env, mark))
        # __exit__ runs on every way out; an unknown one makes no mission call.
        yield Try(mark, inner_flow, (), (), ())

    def context_manager(
        self, node: ast.expr, env: dict[str, Any]
    ) -> tuple[_Function, ast.Call] | None:
        """The script's `@contextmanager` generator a `with` item calls, if it is one
        the folder can inline."""
        if not isinstance(node, ast.Call) or not isinstance(node.func, ast.Name):
            return None
        function = env.get(node.func.id)
        if not isinstance(function, _Function):
            return None
        decorated = any(
            (isinstance(d, ast.Name) and d.id == "contextmanager")
            or (isinstance(d, ast.Attribute) and d.attr == "contextmanager")
            for d in function.node.decorator_list
        )
        yields = [n for n in ast.walk(function.node) if isinstance(n, (ast.Yield, ast.YieldFrom))]
        plain_yield = len(yields) == 1 and any(
            isinstance(n, ast.Expr) and n.value is yields[0] for n in ast.walk(function.node)
        )
        starred = any(isinstance(a, ast.Starred) for a in node.args) or any(
            k.arg is None for k in node.keywords
        )
        if not decorated or not plain_yield or starred:
            return None
        if function.node.name in self.functions_on_stack or len(self.via) >= MAX_INLINE:
            return None
        return function, node

    def try_statement(self, node: ast.Try, env: dict[str, Any]) -> Try:
        before = dict(env)
        body = self.block(node.body, env)
        handlers: list[Handler] = []
        branch_envs: list[dict[str, Any]] = []
        for handler in node.handlers:
            # A handler starts where something in the body raised: what the body
            # assigned may or may not have happened.
            handler_env = dict(before)
            for statement in node.body:
                self.forget_assigned(statement, handler_env)
            if handler.name:
                handler_env[handler.name] = UNKNOWN
            flow = self.block(handler.body, handler_env)
            handlers.append(Handler(self.mark(handler), _catches_all(handler.type), flow))
            branch_envs.append(handler_env)
        orelse = self.block(node.orelse, env)
        for other in branch_envs:
            _merge_into(env, other)
        finalbody = self.block(node.finalbody, env)
        return Try(self.mark(node), body, tuple(handlers), orelse, finalbody)

    def imports(self, node: ast.Import | ast.ImportFrom, env: dict[str, Any]) -> None:
        if isinstance(node, ast.Import):
            for alias in node.names:
                name = alias.asname or alias.name.split(".")[0]
                env[name] = _Module(alias.name) if alias.name == API_MODULE else UNKNOWN
            return
        for alias in node.names:
            name = alias.asname or alias.name
            # The API's names mean the API whichever module re-exports them
            # (`from aeroexec.mission import execute_behavior`).
            if alias.name in MISSION_CALLS:
                env[name] = _Api(MISSION_CALLS[alias.name], alias.name)
            else:
                env[name] = UNKNOWN

    def assignment(
        self, node: ast.Assign | ast.AnnAssign | ast.AugAssign, env: dict[str, Any]
    ) -> Iterator[Node]:
        if node.value is None:  # `x: int`
            return
        nodes, value = self.evaluate_with_calls(node.value, env)
        yield from nodes
        if isinstance(node, ast.AugAssign):
            if isinstance(node.target, ast.Name) and type(node.op) in _BINARY:
                current = env.get(node.target.id, UNKNOWN)
                known = is_known(current) and is_known(value)
                env[node.target.id] = (
                    _constant_result(_BINARY[type(node.op)], current, value) if known else UNKNOWN
                )
            else:
                self.bind(node.target, UNKNOWN, env)
            return
        targets = node.targets if isinstance(node, ast.Assign) else [node.target]
        for target in targets:
            self.bind(target, value, env)

    def bind(self, target: ast.expr, value: Any, env: dict[str, Any]) -> None:
        if isinstance(target, ast.Name):
            mutable = isinstance(value, (list, dict))
            env[target.id] = UNKNOWN if mutable and target.id in self.mutated else value
        elif isinstance(target, (ast.Tuple, ast.List)):
            items = (
                list(value)
                if isinstance(value, (tuple, list)) and len(value) == len(target.elts)
                else [UNKNOWN] * len(target.elts)
            )
            for element, item in zip(target.elts, items, strict=True):
                self.bind(element.value if isinstance(element, ast.Starred) else element, item, env)
        # attributes and subscripts hold nothing the folder tracks

    def forget_assigned(self, node: ast.AST, env: dict[str, Any]) -> None:
        """Names assigned anywhere inside `node` are unknown afterwards."""
        for child in ast.walk(node):
            if isinstance(child, ast.Name) and isinstance(child.ctx, ast.Store):
                env[child.id] = UNKNOWN

    def if_statement(self, node: ast.If, env: dict[str, Any]) -> Iterator[Node]:
        nodes, condition = self.evaluate_with_calls(node.test, env)
        yield from nodes
        if is_known(condition):
            yield from self.block(node.body if condition else node.orelse, env)
            return
        then_env, else_env = dict(env), dict(env)
        arms = (
            ("if", self.block(node.body, then_env)),
            ("else", self.block(node.orelse, else_env)),
        )
        env.clear()
        env.update(then_env)
        _merge_into(env, else_env)
        yield Branch(self.mark(node), arms)

    def for_statement(self, node: ast.For | ast.AsyncFor, env: dict[str, Any]) -> Iterator[Node]:
        nodes, items = self.evaluate_with_calls(node.iter, env)
        yield from nodes
        if isinstance(items, dict):
            items = list(items)  # a dict iterates over its keys
        constant = isinstance(items, (list, tuple, str)) and is_known(items)
        if constant and self.unrolled + len(items) > MAX_UNROLLED:
            self.bounds.append(
                f"the loop at line {node.lineno} left as a loop ({MAX_UNROLLED} iterations "
                "unrolled)"
            )
        elif constant and len(items) <= MAX_UNROLL and not isinstance(node, ast.AsyncFor):
            self.unrolled += len(items)
            if not _jumps_out(node.body):
                for item in items:
                    self.bind(node.target, item, env)
                    yield from self.block(node.body, env)
                yield from self.block(node.orelse, env)
                return
            iterations: list[Flow] = []
            for item in items:
                self.bind(node.target, item, env)
                flow = self.block(node.body, env)
                iterations.append(flow)
                if flow and isinstance(flow[-1], Jump) and flow[-1].kind != "continue":
                    break  # every later item is never reached
            # Which iteration broke out is only known when the mission runs.
            self.forget_assigned(node, env)
            orelse = self.block(node.orelse, env)
            yield Unrolled(self.mark(node), tuple(iterations), orelse)
            return
        self.forget_assigned(node, env)
        body = self.block(node.body, env)
        self.forget_assigned(node, env)
        # A constant sequence too long to unroll still runs its body at least once.
        may_skip = not (constant and len(items) > 0)
        yield Loop(self.mark(node), body, may_skip=may_skip, ends_by_condition=True)
        yield from self.block(node.orelse, env)

    def while_statement(self, node: ast.While, env: dict[str, Any]) -> Iterator[Node]:
        nodes, condition = self.evaluate_with_calls(node.test, env)
        yield from nodes
        if is_known(condition) and not condition:
            yield from self.block(node.orelse, env)
            return
        if is_known(condition) and not nodes:
            unrolled = self.unroll_while(node, env)
            if unrolled is not None:
                yield unrolled
                return
        forever = is_known(condition)
        self.forget_assigned(node, env)
        test_nodes = self.expression_calls(node.test, env)
        body = (
            (*test_nodes, *self.block(node.body, env))
            if not forever
            else self.block(node.body, env)
        )
        self.forget_assigned(node, env)
        yield Loop(self.mark(node), body, may_skip=not forever, ends_by_condition=not forever)
        if not forever:
            yield from self.block(node.orelse, env)

    def unroll_while(self, node: ast.While, env: dict[str, Any]) -> Unrolled | None:
        """A `while` whose condition is a constant the body changes (`n < 3` with `n += 1`),
        run iteration by iteration while the condition stays known: exactly its
        iterations, as a `for` over a constant range. None (and nothing recorded) when
        the condition becomes unknown, or more than MAX_UNROLL iterations would run."""
        assigned = {
            child.id
            for child in ast.walk(node)
            if isinstance(child, ast.Name) and isinstance(child.ctx, ast.Store)
        }
        assigned |= {
            child.target.id
            for child in ast.walk(node)
            if isinstance(child, ast.AugAssign) and isinstance(child.target, ast.Name)
        }
        read = {child.id for child in ast.walk(node.test) if isinstance(child, ast.Name)}
        if not read & assigned:
            return None  # `while True:` and the like: only a jump leaves it
        trial = dict(env)
        calls, unchecked = len(self.calls), dict(self.unchecked)
        iterations: list[Flow] = []
        broke = False
        while True:
            tested, condition = self.evaluate_with_calls(node.test, trial)
            budget = len(iterations) >= MAX_UNROLL or self.unrolled >= MAX_UNROLLED
            if tested or not is_known(condition) or budget:
                del self.calls[calls:]
                self.unchecked = unchecked
                return None
            if not condition:
                break
            self.unrolled += 1
            flow = self.block(node.body, trial)
            iterations.append(flow)
            if flow and isinstance(flow[-1], Jump) and flow[-1].kind != "continue":
                broke = True
                break
        if _jumps_out(node.body):
            # Which iteration broke out is only known when the mission runs.
            self.forget_assigned(node, trial)
        env.clear()
        env.update(trial)
        orelse = () if broke else self.block(node.orelse, env)
        return Unrolled(self.mark(node), tuple(iterations), orelse)

    # -- expressions -----------------------------------------------------------------------
    def expression_calls(self, node: ast.expr, env: dict[str, Any]) -> Flow:
        nodes, _ = self.evaluate_with_calls(node, env)
        return nodes

    def evaluate_with_calls(self, node: ast.expr, env: dict[str, Any]) -> tuple[Flow, Any]:
        """The calls the expression makes (in evaluation order) and its folded value."""
        collected: list[Node] = []
        value = self.evaluate(node, env, collected, 0)
        return tuple(collected), value

    def evaluate(self, node: ast.expr, env: dict[str, Any], out: list[Node], depth: int) -> Any:
        if depth > MAX_EXPRESSION:
            return UNKNOWN
        deeper = depth + 1
        if isinstance(node, ast.Constant):
            return node.value if isinstance(node.value, _CONSTANT_TYPES) else UNKNOWN
        if isinstance(node, ast.Name):
            if node.id in env:
                return env[node.id]
            if node.id in MISSION_CALLS:
                return _Api(MISSION_CALLS[node.id], node.id)
            return UNKNOWN
        if isinstance(node, (ast.List, ast.Tuple)):
            items = []
            for element in node.elts:
                if isinstance(element, ast.Starred):
                    self.evaluate(element.value, env, out, deeper)
                    return UNKNOWN
                items.append(self.evaluate(element, env, out, deeper))
            return items if isinstance(node, ast.List) else tuple(items)
        if isinstance(node, ast.Dict):
            folded: dict[Any, Any] = {}
            for key, item in zip(node.keys, node.values, strict=True):
                if key is None:  # `{**other}`
                    self.evaluate(item, env, out, deeper)
                    return UNKNOWN
                k = self.evaluate(key, env, out, deeper)
                v = self.evaluate(item, env, out, deeper)
                if not isinstance(k, _CONSTANT_TYPES) or isinstance(k, _Unknown):
                    return UNKNOWN
                folded[k] = v
            return folded
        if isinstance(node, ast.Subscript):
            base = self.evaluate(node.value, env, out, deeper)
            if isinstance(node.slice, ast.Slice):
                return UNKNOWN
            index = self.evaluate(node.slice, env, out, deeper)
            if not (isinstance(base, (str, list, tuple, dict)) and is_known(index)):
                return UNKNOWN
            if isinstance(base, dict) and not isinstance(index, _CONSTANT_TYPES):
                return UNKNOWN
            return _constant_result(operator.getitem, base, index)
        if isinstance(node, ast.Attribute):
            base = self.evaluate(node.value, env, out, deeper)
            if isinstance(base, dict) and node.attr == "get":
                return _DictGet(base)
            if node.attr in MISSION_CALLS and (isinstance(base, _Module) or base is UNKNOWN):
                return _Api(MISSION_CALLS[node.attr], node.attr)
            if isinstance(base, str) and node.attr in _STRING_METHODS:
                return _StringMethod(base, node.attr)
            return UNKNOWN
        if isinstance(node, ast.Call):
            return self.call(node, env, out, deeper)
        if isinstance(node, ast.BinOp):
            left = self.evaluate(node.left, env, out, deeper)
            right = self.evaluate(node.right, env, out, deeper)
            function = _BINARY.get(type(node.op))
            if function is None or not (is_known(left) and is_known(right)):
                return UNKNOWN
            if isinstance(left, list):
                left = tuple(left) if isinstance(right, tuple) else left
            return _constant_result(function, left, right)
        if isinstance(node, ast.UnaryOp):
            operand = self.evaluate(node.operand, env, out, deeper)
            if not is_known(operand):
                return UNKNOWN
            if isinstance(node.op, ast.Not):
                return not operand
            if isinstance(node.op, ast.USub):
                return _constant_result(operator.neg, operand)
            if isinstance(node.op, ast.UAdd):
                return _constant_result(operator.pos, operand)
            return UNKNOWN
        if isinstance(node, ast.BoolOp):
            values = [self.evaluate(v, env, out, deeper) for v in node.values]
            if not all(is_known(v) for v in values):
                return UNKNOWN
            result = values[0]
            for value in values[1:]:
                result = (result and value) if isinstance(node.op, ast.And) else (result or value)
            return result
        if isinstance(node, ast.Compare):
            left = self.evaluate(node.left, env, out, deeper)
            rights = [self.evaluate(c, env, out, deeper) for c in node.comparators]
            if not is_known(left) or not all(is_known(r) for r in rights):
                return UNKNOWN
            for op, right in zip(node.ops, rights, strict=True):
                outcome = _constant_result(_COMPARE[type(op)], left, right)
                if outcome is UNKNOWN or not outcome:
                    return outcome
                left = right
            return True
        if isinstance(node, ast.JoinedStr):
            parts = []
            for part in node.values:
                if isinstance(part, ast.Constant):
                    parts.append(str(part.value))
                    continue
                assert isinstance(part, ast.FormattedValue)
                value = self.evaluate(part.value, env, out, deeper)
                if not is_known(value) or part.format_spec is not None or part.conversion != -1:
                    return UNKNOWN
                parts.append(str(value))
            return "".join(parts)
        if isinstance(node, ast.IfExp):
            test = self.evaluate(node.test, env, out, deeper)
            if is_known(test):
                return self.evaluate(node.body if test else node.orelse, env, out, deeper)
            # Both arms' calls are collected only when known to run: not here.
            return UNKNOWN
        # Lambdas, comprehensions, subscripts, dict displays...: evaluated for nothing.
        return UNKNOWN

    def call(self, node: ast.Call, env: dict[str, Any], out: list[Node], depth: int) -> Any:
        function = self.evaluate(node.func, env, out, depth)
        if isinstance(function, _Api):
            out.append(CallNode(self.mission_call(node, function, env, out, depth)))
            return UNKNOWN
        args = [self.evaluate(a, env, out, depth) for a in node.args]
        keywords = {k.arg: self.evaluate(k.value, env, out, depth) for k in node.keywords}
        if isinstance(function, _StringMethod) and not args and not keywords:
            return getattr(function.text, function.method)()
        if isinstance(function, _DictGet) and 1 <= len(args) <= 2 and not keywords:
            key = args[0]
            if not isinstance(key, _CONSTANT_TYPES):
                return UNKNOWN
            return function.mapping.get(key, args[1] if len(args) == 2 else None)
        if (
            isinstance(node.func, ast.Name)
            and node.func.id not in env
            and node.func.id in _BUILTINS
            and not keywords
            and all(is_known(a) for a in args)
        ):
            return _builtin(node.func.id, args)
        if isinstance(function, _Function):
            name = function.node.name
            starred = any(isinstance(a, ast.Starred) for a in node.args) or None in keywords
            if (
                starred
                or name in self.functions_on_stack
                or len(self.functions_on_stack) >= MAX_INLINE
                or self.nesting >= MAX_NESTING
            ):
                return UNKNOWN
            self.returns.append([])
            self.via.append((name, self.mark(node)))
            try:
                body = self.inline(function, args, keywords, env)
            finally:
                self.via.pop()
            values = self.returns.pop()
            out.append(Inline(name, self.mark(node), body))
            if values and all(is_known(v) for v in values) and all(v == values[0] for v in values):
                return values[0]
            return UNKNOWN
        return UNKNOWN

    def inline(
        self,
        function: _Function,
        args: list[Any],
        keywords: dict[str | None, Any],
        env: dict[str, Any],
    ) -> Flow:
        definition = function.node
        local = dict(env)  # module constants and helpers stay visible
        parameters = definition.args
        positional = [*parameters.posonlyargs, *parameters.args]
        defaults = [UNKNOWN] * (len(positional) - len(parameters.defaults))
        defaults += [self.evaluate(d, env, [], 0) for d in parameters.defaults]
        for index, parameter in enumerate(positional):
            if index < len(args):
                local[parameter.arg] = args[index]
            else:
                local[parameter.arg] = keywords.get(parameter.arg, defaults[index])
        for parameter in parameters.kwonlyargs:
            local[parameter.arg] = keywords.get(parameter.arg, UNKNOWN)
        for extra in (parameters.vararg, parameters.kwarg):
            if extra is not None:
                local[extra.arg] = UNKNOWN
        self.functions_on_stack.append(definition.name)
        try:
            return self.block(definition.body, local)
        finally:
            self.functions_on_stack.pop()

    def mission_call(
        self, node: ast.Call, api: _Api, env: dict[str, Any], out: list[Node], depth: int
    ) -> MissionCall:
        mark = self.mark(node)
        behavior: str | None = None
        name_mark = mark
        positional: list[Mark] = []
        args = list(node.args)
        named_by_keyword = False
        if args and not isinstance(args[0], ast.Starred):
            first = args.pop(0)
            name_mark = self.mark(first)
            value = self.evaluate(first, env, out, depth)
            behavior = value if isinstance(value, str) else None
        elif not args:
            for keyword in node.keywords:
                if keyword.arg in ("name", "behavior"):
                    value = self.evaluate(keyword.value, env, out, depth)
                    behavior = value if isinstance(value, str) else None
                    name_mark = self.mark(keyword.value)
                    named_by_keyword = True
                    break
        for extra in args:
            self.evaluate(extra, env, out, depth)
            positional.append(self.mark(extra))
        arguments: list[CallArgument] = []
        for keyword in node.keywords:
            if keyword.arg is None:
                # **{'angle': 90} with a literal dict is checked like keywords.
                if isinstance(keyword.value, ast.Dict):
                    for key, value in zip(keyword.value.keys, keyword.value.values, strict=True):
                        if isinstance(key, ast.Constant) and isinstance(key.value, str):
                            folded = self.evaluate(value, env, out, depth)
                            arguments.append(
                                CallArgument(key.value, _argument(folded), self.mark(key))
                            )
                continue
            if named_by_keyword and keyword.arg in ("name", "behavior"):
                continue
            folded = self.evaluate(keyword.value, env, out, depth)
            arguments.append(CallArgument(keyword.arg, _argument(folded), self.mark(keyword)))
        call = MissionCall(
            api.kind,
            api.function,
            behavior,
            tuple(arguments),
            tuple(positional),
            mark,
            name_mark,
            tuple(self.via),
        )
        self.calls.append(call)
        if behavior is None:
            self.unchecked[(mark.line, mark.column)] = mark
        return call


def _argument(value: Any) -> Any:
    """A folded value as the argument checks see it: lists for sequences."""
    if isinstance(value, (list, tuple)):
        return [_argument(v) for v in value]
    return value if isinstance(value, _CONSTANT_TYPES) else UNKNOWN


def api_call_sites(tree: ast.AST) -> Iterator[ast.Call]:
    """Every call whose function is named like a mission API call (anywhere in the file)."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            func = node.func
            name = (
                func.id
                if isinstance(func, ast.Name)
                else func.attr
                if isinstance(func, ast.Attribute)
                else None
            )
            if name in MISSION_CALLS:
                yield node


def fold_mission(tree: ast.Module, file: str, lines: Sequence[str]) -> FoldedMission:
    """Fold the script; API call sites the folder never reached (in a function nobody
    calls, a class) are added as written, so every call of the file is checked."""
    folder = Folder(file, lines)
    folded = folder.fold(tree)
    reached = {(c.mark.line, c.mark.column) for c in folded.calls}
    extra: list[MissionCall] = []
    module_env: dict[str, Any] = {}
    for site in api_call_sites(tree):
        mark = folder.mark(site)
        if (mark.line, mark.column) in reached:
            continue
        name = site.func.id if isinstance(site.func, ast.Name) else site.func.attr  # type: ignore[union-attr]
        call = folder.mission_call(site, _Api(MISSION_CALLS[name], name), module_env, [], 0)
        extra.append(call)
    calls = sorted([*folded.calls, *extra], key=lambda c: (c.mark.line, c.mark.column))
    return FoldedMission(
        folded.flow,
        folded.entry,
        tuple(calls),
        tuple(sorted(folder.unchecked.values(), key=lambda m: (m.line, m.column))),
        folded.bounds,
    )
