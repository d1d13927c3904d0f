"""Fold a mission script into the sequence of mission API calls it makes, without running it.

The script's AST is interpreted abstractly, from its entry point (`runMission()`, or
`run_mission()` / `main()`, after the module's top level, as `aeroexec run` does):

* constants are folded: a behavior name in a variable (`name = 'TAKE_OFF'`), string
  arithmetic, a loop over a literal list of names (unrolled), helper functions called
  with constant arguments (inlined, also for their return value), aliases of the API
  (`go = api.executeBehavior`, `from executive_engine_api import executeBehavior as go`);
* what depends on the run (a belief, a behavior's result, a loop over data) stays
  unknown: an `if` on it keeps both branches, a loop on it becomes a `Loop` node.

The result is a `Flow`: mission calls (`CallNode`, each a `MissionCall` with folded
arguments), `Branch`, `Loop`, `Inline` (a helper's body) and the jumps `Return`,
`Break`, `Continue`. `aeroexec.verifier.mission_run` runs it against the executive; the
per-call rules (AX70x) check every `MissionCall` it contains. A call whose behavior
name cannot be folded is "not checked" (AX708 names its line).

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
class Inline:
    name: str
    mark: Mark
    body: Flow


@dataclass(frozen=True, slots=True)
class Jump:
    kind: str  # "return" | "break" | "continue" | "raise"
    mark: Mark


Node = CallNode | Branch | Loop | Inline | Jump
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


class _Returned(Exception):
    pass


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
        if isinstance(node, ast.Expr):
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
            for item in node.items:
                yield from self.expression_calls(item.context_expr, env)
                if item.optional_vars is not None:
                    self.bind(item.optional_vars, UNKNOWN, env)
            yield from self.block(node.body, env)
        elif isinstance(node, ast.Try) or type(node).__name__ == "TryStar":
            # The path where nothing raises; handlers only run on an exception.
            yield from self.block(node.body, env)  # type: ignore[attr-defined]
            yield from self.block(node.orelse, env)  # type: ignore[attr-defined]
            yield from self.block(node.finalbody, env)  # type: ignore[attr-defined]
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
            env[target.id] = value
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
        for name in set(then_env) | set(else_env):
            a, b = then_env.get(name, UNKNOWN), else_env.get(name, UNKNOWN)
            env[name] = a if a is b or (is_known(a) and is_known(b) and a == b) else UNKNOWN
        yield Branch(self.mark(node), arms)

    def for_statement(self, node: ast.For | ast.AsyncFor, env: dict[str, Any]) -> Iterator[Node]:
        nodes, items = self.evaluate_with_calls(node.iter, env)
        yield from nodes
        jumps = any(isinstance(child, (ast.Break, ast.Continue)) for child in ast.walk(node))
        constant = isinstance(items, (list, tuple, str)) and is_known(items)
        if constant and not jumps and len(items) <= MAX_UNROLL:
            for item in items:
                self.bind(node.target, item, env)
                yield from self.block(node.body, env)
            yield from self.block(node.orelse, env)
            return
        self.forget_assigned(node, env)
        body = self.block(node.body, env)
        self.forget_assigned(node, env)
        yield Loop(self.mark(node), body, may_skip=True, ends_by_condition=True)
        yield from self.block(node.orelse, env)

    def while_statement(self, node: ast.While, env: dict[str, Any]) -> Iterator[Node]:
        nodes, condition = self.evaluate_with_calls(node.test, env)
        yield from nodes
        if is_known(condition) and not condition:
            yield from self.block(node.orelse, env)
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
        if isinstance(node, ast.Attribute):
            base = self.evaluate(node.value, env, out, deeper)
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
            body = self.inline(function, args, keywords, env)
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
            api.kind, api.function, behavior, tuple(arguments), tuple(positional), mark, name_mark
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
    )
