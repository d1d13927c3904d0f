"""How messages show things: a path relative to the working directory when inside it (as
ruff and pytest do), else as given; a behavior's arguments as `name=value` pairs, the same
in `run`'s printout, `replay` and `diff`."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any


def shown(path: str | Path) -> str:
    text = str(path)
    try:
        relative = os.path.relpath(text)
    except ValueError:  # another drive (Windows)
        return text
    if relative == ".":
        return str(Path(text).resolve())
    return text if relative.startswith("..") else relative


def shown_arguments(arguments: dict[str, Any]) -> str:
    """`count=2 coordinates=[3, 5.5, 1.3]` (whole floats without their `.0`)."""
    return " ".join(f"{name}={_value(value)}" for name, value in arguments.items())


def _value(value: Any) -> str:
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, float) and value.is_integer():
        return str(int(value))
    return str(value)
