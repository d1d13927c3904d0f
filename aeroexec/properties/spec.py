"""Property files: YAML lists of named formulas, and the built-in set `aeroexec:safety`.

    parameters:                    # optional: numbers formulas name
      ceiling_m: 120
    properties:
      - name: ceiling
        formula: always(altitude <= ceiling_m)
        severity: error            # error (default) | warning | note
        description: never above {ceiling_m} m
        action: land               # online only: land | hold | rtl | abort

The YAML is read by the catalog's safe loader (no tag runs, every value keeps its
`file:line:col`); every problem is a `PropertyError` at its place.

A parameter is set for the whole set a command loads (`--spec` is repeatable): a file
given later sets it again, so a file of parameters alone changes a bound of the built-in
set (`--spec aeroexec:safety --spec slower.yaml` with `parameters: {land_within_s: 60}`).
A parameter no formula of the set reads is an error at its place (a misspelt name would
change nothing).
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from aeroexec.catalog.yamlnodes import YNode, load_yaml
from aeroexec.errors import CatalogError, Mark, PropertyError
from aeroexec.inputs import read_text
from aeroexec.properties.formula import Formula, compile_formula
from aeroexec.properties.lexer import FORBIDDEN_WORDS, KEYWORDS
from aeroexec.properties.signals import is_known_signal

BUILTIN_PREFIX = "aeroexec:"
_DATA = Path(__file__).resolve().parent.parent / "data" / "properties"
BUILTINS = {"aeroexec:safety": _DATA / "safety.yaml"}
SEVERITIES = ("error", "warning", "note")
ACTIONS = ("land", "hold", "rtl", "abort")
_FILE_KEYS = ("parameters", "properties")
_KEYS = ("name", "formula", "severity", "description", "action")
_NAME_CHARS = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-.")
_PARAMETER_NAME = re.compile(r"[A-Za-z_][A-Za-z_0-9]*")
#: `{name}` in a description: the parameter's value.
_PLACEHOLDER = re.compile(r"\{([A-Za-z_][A-Za-z_0-9]*)\}")


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
class Parameter:
    name: str
    value: float
    #: As a formula's number reads it (decimal).
    text: str
    #: Where it is set (the last file of the set that sets it).
    mark: Mark

    @property
    def where(self) -> str:
        return f"{self.mark.file}:{self.mark.line}" if self.mark.line else self.mark.file


@dataclass(frozen=True)
class PropertySet:
    properties: tuple[Property, ...]
    sources: tuple[str, ...]
    #: The parameters the formulas read, with the values they were given.
    parameters: tuple[Parameter, ...] = ()
    #: Each file's name and text, as read: what another process (a replay's worker, on
    #: this machine or a cluster's) loads the same set from (`load_property_documents`).
    documents: tuple[tuple[str, str], ...] = ()

    def find(self, name: str) -> Property | None:
        return next((p for p in self.properties if p.name == name), None)

    def signals(self) -> tuple[str, ...]:
        seen: dict[str, None] = {}
        for prop in self.properties:
            seen.update(dict.fromkeys(prop.formula.signals))
        return tuple(seen)


@dataclass(frozen=True)
class _Document:
    file: str
    root: YNode
    lines: list[str]


def load_properties(specs: list[str] | tuple[str, ...], *, alone: bool = False) -> PropertySet:
    """Every property of `specs` (files or built-in names such as `aeroexec:safety`),
    in order, with the parameters the files set (a later file's value wins); a name
    defined twice is an error at its second place. `alone`: a file checked by itself
    (`verify`), whose parameters may be read by files given with it."""
    return load_property_documents([(spec, _read(spec)) for spec in specs], alone=alone)


def load_property_documents(
    texts: Sequence[tuple[str, str]], *, alone: bool = False
) -> PropertySet:
    """`load_properties` of files already read: (name, text) of each, in order."""
    specs = [name for name, _ in texts]
    documents = [_document(text, name) for name, text in texts]
    parameters: dict[str, Parameter] = {}
    for document in documents:
        for parameter in _parameters(document):
            parameters[parameter.name] = parameter
    values = {name: (parameter.text, parameter.mark) for name, parameter in parameters.items()}
    properties: list[Property] = []
    seen: dict[str, Property] = {}
    read: set[str] = set()
    for document in documents:
        for prop in _properties(document, values):
            earlier = seen.get(prop.name)
            if earlier is not None:
                raise PropertyError(
                    f"property '{prop.name}' is already defined at {earlier.where}", prop.mark
                )
            seen[prop.name] = prop
            properties.append(prop)
            read.update(prop.formula.parameters)
    for name, parameter in parameters.items():
        if name not in read and not alone:
            raise PropertyError(
                f"parameter '{name}' is read by no formula of {', '.join(specs)}",
                parameter.mark,
            )
    used = tuple(p for name, p in parameters.items() if name in read)
    return PropertySet(tuple(properties), tuple(specs), used, tuple(texts))


def _read(spec: str) -> str:
    if spec.startswith(BUILTIN_PREFIX):
        path = BUILTINS.get(spec)
        if path is None:
            known = ", ".join(sorted(BUILTINS))
            raise PropertyError(f"no built-in property set '{spec}' (there is {known})")
        return path.read_text(encoding="utf-8")
    return read_text(spec, "a property file", PropertyError)


def parse_properties(text: str, file: str) -> list[Property]:
    """The properties of one file, with its own parameters."""
    document = _document(text, file)
    values = {p.name: (p.text, p.mark) for p in _parameters(document)}
    return _properties(document, values)


def _document(text: str, file: str) -> _Document:
    try:
        root = load_yaml(text, file)
    except CatalogError as exc:
        raise PropertyError(exc.message, exc.mark) from None
    if root is None:
        raise PropertyError("empty property file: it needs a 'properties' list", Mark(file, 1, 1))
    if not root.is_map:
        raise PropertyError("a property file is a mapping with a 'properties' list", root.mark)
    for key, _ in root.items():
        if key not in _FILE_KEYS:
            raise PropertyError(
                f"unknown key '{key}' (expected 'properties' or 'parameters')",
                root.key_marks[key],
            )
    items = root.get("properties")
    if (items is None and root.get("parameters") is None) or (
        items is not None and not items.is_list
    ):
        where = items.mark if items is not None else root.mark
        raise PropertyError("'properties' must be a list of properties", where)
    return _Document(file, root, text.splitlines())


def _parameters(document: _Document) -> list[Parameter]:
    node = document.root.get("parameters")
    if node is None:
        return []
    if not node.is_map:
        raise PropertyError("'parameters' must be a mapping of names to numbers", node.mark)
    found = []
    for name, value in node.items():
        mark = node.key_marks[name]
        if not isinstance(name, str) or not _PARAMETER_NAME.fullmatch(name):
            raise PropertyError(
                f"parameter name '{name}': use letters, digits and '_', not first a digit", mark
            )
        if name in KEYWORDS or name in FORBIDDEN_WORDS or is_known_signal(name):
            what = "a signal" if is_known_signal(name) else "a word of the formula language"
            raise PropertyError(f"parameter name '{name}' is {what}", mark)
        number = value.value
        if isinstance(number, bool) or not isinstance(number, int | float):
            raise PropertyError(f"parameter '{name}' must be a number", value.mark)
        if not math.isfinite(number):
            raise PropertyError(f"parameter '{name}' must be a finite number", value.mark)
        found.append(Parameter(name, float(number), repr(number), mark))
    return found


def _properties(document: _Document, values: dict[str, tuple[str, Mark]]) -> list[Property]:
    items = document.root.get("properties")
    if items is None:
        return []
    return [_property(item, document.lines, values) for item in items.value]


def _property(node: YNode, lines: list[str], parameters: dict[str, tuple[str, Mark]]) -> Property:
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
        formula_node.value, _content(formula_node.mark, lines), is_known_signal, parameters
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
    description = _PLACEHOLDER.sub(
        lambda m: parameters[m[1]][0] if m[1] in parameters else m[0], description
    )
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
