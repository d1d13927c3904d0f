"""YAML to plain values that remember where they came from.

PyYAML composes the document into nodes (with the C parser when it is built in); we
turn nodes into `YNode`s ourselves instead of letting a constructor run, so that:

* no YAML tag is ever executed (only the core schema's tags are accepted);
* aliases are followed under a budget, so an alias bomb fails fast instead of
  expanding a billion nodes, and recursive aliases are refused;
* every value keeps its `file:line:col`, and every mapping key its own mark.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import yaml

from aeroexec.errors import CatalogError, Mark

try:  # The C parser is much faster on large catalogs; fall back when PyYAML lacks it.
    _Loader: type = yaml.CSafeLoader  # type: ignore[attr-defined]
except AttributeError:  # pragma: no cover - depends on how PyYAML was built
    _Loader = yaml.SafeLoader

HAS_C_LOADER = _Loader is not yaml.SafeLoader

_CORE = "tag:yaml.org,2002:"
_SCALAR_TAGS = {_CORE + t for t in ("str", "int", "float", "bool", "null")}
#: Nodes visited per document, aliases counted each time they are followed. Large enough
#: for a 100,000-entry catalog, small enough that a "billion laughs" stops in milliseconds.
DEFAULT_NODE_BUDGET = 5_000_000


@dataclass(frozen=True, slots=True)
class YNode:
    """A YAML value with its mark. `value` is dict[str, YNode], list[YNode] or a scalar."""

    value: Any
    mark: Mark
    key_marks: dict[str, Mark] = field(default_factory=dict, compare=False)
    duplicate_keys: tuple[tuple[str, Mark], ...] = ()

    @property
    def is_map(self) -> bool:
        return isinstance(self.value, dict)

    @property
    def is_list(self) -> bool:
        return isinstance(self.value, list)

    def get(self, key: str) -> YNode | None:
        return self.value.get(key) if isinstance(self.value, dict) else None

    def items(self) -> Iterator[tuple[str, YNode]]:
        return iter(self.value.items()) if isinstance(self.value, dict) else iter(())

    def plain(self) -> Any:
        """The value without marks (for display and JSON)."""
        if isinstance(self.value, dict):
            return {k: v.plain() for k, v in self.value.items()}
        if isinstance(self.value, list):
            return [v.plain() for v in self.value]
        return self.value


def _mark(file: str, node: yaml.Node) -> Mark:
    return Mark(file, node.start_mark.line + 1, node.start_mark.column + 1)


class _Builder:
    def __init__(self, file: str, budget: int) -> None:
        self.file = file
        self.budget = budget
        self.constructor = yaml.constructor.SafeConstructor()
        self.in_progress: set[int] = set()

    def build(self, node: yaml.Node) -> YNode:
        self.budget -= 1
        if self.budget < 0:
            raise CatalogError(
                "document expands to too many nodes (alias bomb?); refusing to expand it",
                _mark(self.file, node),
            )
        if isinstance(node, yaml.ScalarNode):
            return self._scalar(node)
        if id(node) in self.in_progress:
            raise CatalogError("recursive alias: a node contains itself", _mark(self.file, node))
        self.in_progress.add(id(node))
        try:
            if isinstance(node, yaml.SequenceNode):
                self._check_tag(node, _CORE + "seq")
                return YNode([self.build(item) for item in node.value], _mark(self.file, node))
            if isinstance(node, yaml.MappingNode):
                return self._mapping(node)
        finally:
            self.in_progress.discard(id(node))
        raise CatalogError(f"unsupported YAML node {type(node).__name__}", _mark(self.file, node))

    def _check_tag(self, node: yaml.Node, expected: str) -> None:
        if node.tag != expected:
            raise CatalogError(
                f"YAML tag {node.tag!r} is not allowed (aeroexec never executes tags)",
                _mark(self.file, node),
            )

    def _scalar(self, node: yaml.ScalarNode) -> YNode:
        if node.tag not in _SCALAR_TAGS:
            self._check_tag(node, _CORE + "str")
        try:
            value = self.constructor.construct_object(node, deep=True)
        except (yaml.constructor.ConstructorError, ValueError, OverflowError) as exc:
            raise CatalogError(
                f"bad scalar {node.value!r}: {exc}", _mark(self.file, node)
            ) from None
        return YNode(value, _mark(self.file, node))

    def _mapping(self, node: yaml.MappingNode) -> YNode:
        self._check_tag(node, _CORE + "map")
        values: dict[str, YNode] = {}
        key_marks: dict[str, Mark] = {}
        duplicates: list[tuple[str, Mark]] = []
        for key_node, value_node in node.value:
            if key_node.tag == _CORE + "merge":
                raise CatalogError(
                    "YAML merge keys ('<<') are not supported", _mark(self.file, key_node)
                )
            key = self.build(key_node)
            if isinstance(key.value, (dict, list)):
                raise CatalogError("a mapping key must be a scalar", key.mark)
            name = str(key.value)
            if name in values:
                duplicates.append((name, key.mark))
            values[name] = self.build(value_node)
            key_marks[name] = key.mark
        return YNode(values, _mark(self.file, node), key_marks, tuple(duplicates))


def load_yaml(text: str, file: str, *, budget: int = DEFAULT_NODE_BUDGET) -> YNode | None:
    """Parse one YAML document into `YNode`s; `None` for an empty document.

    Raises `CatalogError` (with `file:line:col`) for syntax errors, several documents,
    disallowed tags, alias bombs and recursive aliases.
    """
    loader = _Loader(text)
    try:
        node = loader.get_single_node()
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = Mark(file, mark.line + 1, mark.column + 1) if mark else Mark(file)
        problem = exc.problem or exc.context or "invalid YAML"
        raise CatalogError(f"invalid YAML: {problem}", where) from None
    except yaml.YAMLError as exc:
        raise CatalogError(f"invalid YAML: {exc}", Mark(file, 1, 1)) from None
    finally:
        loader.dispose()
    if node is None:
        return None
    return _Builder(file, budget).build(node)
