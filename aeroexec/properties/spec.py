"""Property files: YAML lists of named formulas, and the built-in set `aeroexec:safety`.

    properties:
      - name: ceiling
        formula: always(altitude <= 120)
        severity: error            # error (default) | warning | note
        description: never above 120 m
        action: land               # online only: land | hold | rtl | abort

The YAML is read by the catalog's safe loader (no tag runs, every value keeps its
`file:line:col`); every problem is a `PropertyError` at its place.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from aeroexec.catalog.yamlnodes import YNode, load_yaml
from aeroexec.errors import CatalogError, Mark, PropertyError
from aeroexec.inputs import read_text
from aeroexec.properties.formula import Formula, compile_formula
from aeroexec.properties.signals import is_known_signal

BUILTIN_PREFIX = "aeroexec:"
_DATA = Path(__file__).resolve().parent.parent / "data" / "properties"
BUILTINS = {"aeroexec:safety": _DATA / "safety.yaml"}
SEVERITIES = ("error", "warning", "note")
ACTIONS = ("land", "hold", "rtl", "abort")
_KEYS = ("name", "formula", "severity", "description", "action")
_NAME_CHARS = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-.")


@dataclass(frozen=True, eq=False)
class Property:
    name: str
    formula: Formula
    severity: str
    description: str
    action: str | None
    #: Where the property is defined (its `name`'s place).
    mark: Mark

    @property
    def where(self) -> str:
        """`spec.yaml:LINE`, as messages cite it."""
        return f"{self.mark.file}:{self.mark.line}" if self.mark.line else self.mark.file


@dataclass(frozen=True)
class PropertySet:
    properties: tuple[Property, ...]
    sources: tuple[str, ...]

    def find(self, name: str) -> Property | None:
        return next((p for p in self.properties if p.name == name), None)

    def signals(self) -> tuple[str, ...]:
        seen: dict[str, None] = {}
        for prop in self.properties:
            seen.update(dict.fromkeys(prop.formula.signals))
        return tuple(seen)


def load_properties(specs: list[str] | tuple[str, ...]) -> PropertySet:
    """Every property of `specs` (files or built-in names such as `aeroexec:safety`),
    in order; a name defined twice is an error at its second place."""
    properties: list[Property] = []
    seen: dict[str, Property] = {}
    for spec in specs:
        for prop in _load_one(spec):
            earlier = seen.get(prop.name)
            if earlier is not None:
                raise PropertyError(
                    f"property '{prop.name}' is already defined at {earlier.where}", prop.mark
                )
            seen[prop.name] = prop
            properties.append(prop)
    return PropertySet(tuple(properties), tuple(specs))


def _load_one(spec: str) -> list[Property]:
    if spec.startswith(BUILTIN_PREFIX):
        path = BUILTINS.get(spec)
        if path is None:
            known = ", ".join(sorted(BUILTINS))
            raise PropertyError(f"no built-in property set '{spec}' (there is {known})")
        return parse_properties(path.read_text(encoding="utf-8"), spec)
    return parse_properties(read_text(spec, "a property file", PropertyError), spec)


def parse_properties(text: str, file: str) -> list[Property]:
    try:
        root = load_yaml(text, file)
    except CatalogError as exc:
        raise PropertyError(exc.message, exc.mark) from None
    if root is None:
        raise PropertyError("empty property file: it needs a 'properties' list", Mark(file, 1, 1))
    if not root.is_map:
        raise PropertyError("a property file is a mapping with a 'properties' list", root.mark)
    for key, _ in root.items():
        if key != "properties":
            raise PropertyError(f"unknown key '{key}' (expected 'properties')", root.key_marks[key])
    items = root.get("properties")
    if items is None or not items.is_list:
        where = items.mark if items is not None else root.mark
        raise PropertyError("'properties' must be a list of properties", where)
    lines = text.splitlines()
    return [_property(item, lines) for item in items.value]


def _property(node: YNode, lines: list[str]) -> Property:
    if not node.is_map:
        raise PropertyError("a property is a mapping with 'name' and 'formula'", node.mark)
    for key, _ in node.items():
        if key not in _KEYS:
            raise PropertyError(
                f"unknown key '{key}' (a property has {', '.join(_KEYS)})", node.key_marks[key]
            )
    name_node = _text(node, "name", required=True)
    assert name_node is not None
    name = name_node.value
    if not name or not set(name) <= _NAME_CHARS:
        raise PropertyError(
            f"property name '{name}': use letters, digits, '_', '-' and '.'", name_node.mark
        )
    formula_node = _text(node, "formula", required=True)
    assert formula_node is not None
    formula = compile_formula(
        formula_node.value, _content(formula_node.mark, lines), is_known_signal
    )
    severity_node = _text(node, "severity")
    severity = severity_node.value if severity_node else "error"
    if severity not in SEVERITIES:
        assert severity_node is not None
        raise PropertyError(
            f"severity '{severity}': expected one of {', '.join(SEVERITIES)}", severity_node.mark
        )
    action_node = _text(node, "action")
    action = action_node.value if action_node else None
    if action is not None and action not in ACTIONS:
        assert action_node is not None
        raise PropertyError(
            f"action '{action}': expected one of {', '.join(ACTIONS)}", action_node.mark
        )
    if action is not None and formula.window_ticks() is None:
        assert action_node is not None
        raise PropertyError(
            f"action '{action}' needs a formula always(BODY) whose BODY looks a bounded "
            "time back and ahead: it is judged during the flight, tick by tick",
            action_node.mark,
        )
    description_node = _text(node, "description")
    description = " ".join(description_node.value.split()) if description_node else ""
    return Property(name, formula, severity, description, action, name_node.mark)


def _text(node: YNode, key: str, *, required: bool = False) -> YNode | None:
    value = node.get(key)
    if value is None:
        if required:
            raise PropertyError(f"a property needs '{key}'", node.mark)
        return None
    if not isinstance(value.value, str):
        raise PropertyError(f"'{key}' must be text", value.mark)
    return value


def _content(mark: Mark, lines: list[str]) -> Mark:
    """Where a scalar's text begins: after its opening quote when it is quoted."""
    if 0 < mark.line <= len(lines):
        line = lines[mark.line - 1]
        if 0 < mark.column <= len(line) and line[mark.column - 1] in "\"'":
            return Mark(mark.file, mark.line, mark.column + 1)
    return mark
