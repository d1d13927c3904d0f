"""Check a concrete argument set against a behavior's argument specs.

Used by the behavior specialist's `check_behavior_format` service and by the verifier's
mission checks, so both say the same thing in the same words.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from aeroexec.catalog.model import ArgumentKind, ArgumentSpec, BehaviorDescriptor


@dataclass(frozen=True, slots=True)
class ArgumentCheck:
    """`errors` empty means valid; `values` are keyed by the catalog's spelling."""

    errors: tuple[str, ...]
    values: Mapping[str, Any] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return not self.errors


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _show(value: Any) -> str:
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_show(v) for v in value) + "]"
    if isinstance(value, float) and value.is_integer():
        return str(int(value))
    return repr(value) if isinstance(value, str) else str(value)


def check_value(behavior: str, spec: ArgumentSpec, value: Any) -> tuple[str | None, Any]:
    """(error or None, normalized value) for one argument."""
    prefix = f"{behavior}: {spec.name}"
    if spec.kind is ArgumentKind.INVALID:
        return f"{prefix} has a malformed specification in the catalog", value
    if spec.kind is ArgumentKind.TEXT:
        if isinstance(value, str):
            return None, value
        return f"{prefix} needs text, got {_show(value)}", value
    if spec.kind is ArgumentKind.SYMBOLS:
        if isinstance(value, str):
            for symbol in spec.symbols:
                if symbol.casefold() == value.casefold():
                    return None, symbol
        return f"{prefix} needs {spec.describe()}, got {_show(value)}", value
    return _check_range(prefix, spec, value)


def _check_range(prefix: str, spec: ArgumentSpec, value: Any) -> tuple[str | None, Any]:
    assert spec.minimum is not None and spec.maximum is not None
    if spec.dimensions == 1 and _is_number(value):
        numbers = [value]
    elif isinstance(value, (list, tuple)):
        numbers = list(value)
    else:
        return f"{prefix} needs {spec.describe()}, got {_show(value)}", value
    problem = None
    if len(numbers) != spec.dimensions:
        problem = f"got {len(numbers)}"
    elif not all(_is_number(n) for n in numbers):
        problem = f"got {_show(value)}"
    else:
        outside = [n for n in numbers if not spec.minimum <= n <= spec.maximum]
        if outside:
            problem = f"got {_show(value)} ({_show(outside[0])} is outside)"
    if problem:
        return f"{prefix} needs {spec.describe()}, {problem}", value
    if spec.dimensions == 1:
        return None, numbers[0]
    return None, [float(n) if isinstance(n, float) else n for n in numbers]


def check_arguments(descriptor: BehaviorDescriptor, arguments: Mapping[str, Any]) -> ArgumentCheck:
    """Validate `arguments` (names matched case-insensitively) for `descriptor`."""
    errors: list[str] = []
    values: dict[str, Any] = {}
    for given, value in arguments.items():
        spec = descriptor.argument(str(given))
        if spec is None:
            known = ", ".join(s.name for s in descriptor.arguments) or "none"
            errors.append(f"{descriptor.name}: unknown argument '{given}' (arguments: {known})")
            continue
        if spec.name in values:
            errors.append(f"{descriptor.name}: {spec.name} given twice")
            continue
        error, normalized = check_value(descriptor.name, spec, value)
        if error:
            errors.append(error)
        else:
            values[spec.name] = normalized
    return ArgumentCheck(tuple(errors), values)
