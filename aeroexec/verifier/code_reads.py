"""The argument names a behavior class reads, found in its source's AST (never run).

For a behavior that declares no `argument_names`, the verifier reads its class's
source file with `ast` and collects the constant keys its hooks look up in their
arguments: `args["TEMPERATURE"]`, `args.get("TEMPERATURE", 20)`, `"TEMPERATURE" in args`
on `on_start`'s parameter (whatever it is called), and the same on `self.arguments`
in any method. A look-up the AST cannot name (`args[key]`, `**args`, iterating over
them, passing them on to another function), or a base class other than `Behavior`
(whose hooks are elsewhere), makes the set incomplete: then only the names it did find
are compared (the catalog may define more).
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path


@dataclass(frozen=True, slots=True)
class ArgumentsRead:
    #: Names as the code spells them, in the order first read.
    names: tuple[str, ...]
    #: False when some look-up could not be named (the code may read more).
    complete: bool


def _module(file: str) -> ast.Module | None:
    try:
        status = Path(file).stat()
    except OSError:
        return None
    return _parsed(file, status.st_mtime_ns, status.st_size)


@lru_cache(maxsize=64)
def _parsed(file: str, mtime_ns: int, size: int) -> ast.Module | None:
    """One parse per version of a file (several catalogs name the same behaviors)."""
    try:
        return ast.parse(Path(file).read_bytes(), filename=file)
    except (OSError, SyntaxError, ValueError, RecursionError, MemoryError):
        return None


def _find_class(tree: ast.Module, name: str, line: int) -> ast.ClassDef | None:
    found = [n for n in ast.walk(tree) if isinstance(n, ast.ClassDef) and n.name == name]
    for node in found:  # the one the class's own mark points at (decorators included)
        first = min([node.lineno, *(d.lineno for d in node.decorator_list)])
        if first <= line <= node.lineno or not line:
            return node
    return found[0] if len(found) == 1 else None


def _is_arguments(node: ast.expr, parameters: set[str]) -> bool:
    if isinstance(node, ast.Name):
        return node.id in parameters
    return (
        isinstance(node, ast.Attribute)
        and node.attr in ("arguments", "_arguments")
        and isinstance(node.value, ast.Name)
        and node.value.id == "self"
    )


def _key(node: ast.expr) -> str | None:
    return node.value if isinstance(node, ast.Constant) and isinstance(node.value, str) else None


def arguments_read(file: str, class_name: str, line: int = 0) -> ArgumentsRead | None:
    """What the class reads from its arguments; None when its source cannot be
    parsed or the class is not found in it."""
    tree = _module(file)
    if tree is None:
        return None
    cls = _find_class(tree, class_name, line)
    if cls is None:
        return None
    names: dict[str, None] = {}
    # Hooks inherited from a class other than Behavior are not in this class's body.
    complete = all(
        (isinstance(base, ast.Name) and base.id == "Behavior")
        or (isinstance(base, ast.Attribute) and base.attr == "Behavior")
        for base in cls.bases
    )
    for method in cls.body:
        if not isinstance(method, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        parameters: set[str] = set()
        positional = [*method.args.posonlyargs, *method.args.args]
        if method.name == "on_start" and len(positional) >= 2:
            parameters.add(positional[1].arg)
        # Uses of the arguments that are look-ups by a constant key; any other use
        # of them (passed on, iterated, indexed by a variable) leaves the set open.
        understood: set[int] = set()
        for node in ast.walk(method):
            if isinstance(node, ast.Subscript) and _is_arguments(node.value, parameters):
                understood.add(id(node.value))
                key = _key(node.slice)
                if key is None:
                    complete = False
                else:
                    names.setdefault(key)
            elif (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Attribute)
                and _is_arguments(node.func.value, parameters)
            ):
                understood.add(id(node.func.value))
                key = _key(node.args[0]) if node.args else None
                if node.func.attr in ("get", "pop") and key is not None:
                    names.setdefault(key)
                elif node.func.attr not in ("keys",):
                    complete = False
            elif isinstance(node, ast.Compare) and any(
                isinstance(op, (ast.In, ast.NotIn)) for op in node.ops
            ):
                for operand in node.comparators:
                    if _is_arguments(operand, parameters):
                        understood.add(id(operand))
                        key = _key(node.left)
                        if key is None:
                            complete = False
                        else:
                            names.setdefault(key)
        for node in ast.walk(method):
            if (
                isinstance(node, (ast.Name, ast.Attribute))
                and isinstance(getattr(node, "ctx", None), ast.Load)
                and _is_arguments(node, parameters)
                and id(node) not in understood
            ):
                complete = False  # the arguments go somewhere the AST does not follow
    return ArgumentsRead(tuple(names), complete)
