"""A package's public names, each imported from its module when first used (PEP 562), so
that importing the package costs nothing its caller does not use (`verify` needs
`Behavior`, not the executive and the simulator that `aeroexec.executive` also names)."""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any


def lazy_exports(
    package: str, where: Mapping[str, str], namespace: dict[str, Any]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The package's `__getattr__` and `__dir__`: `where` maps each public name to the
    submodule defining it; a name once loaded is kept in `namespace` (the package's
    globals), so the next use is an ordinary attribute."""

    def __getattr__(name: str) -> Any:
        module = where.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{module}"), name)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted({*namespace.get("__all__", ()), *where})

    return __getattr__, __dir__
