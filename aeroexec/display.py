"""How messages show a path: relative to the working directory when inside it (as ruff
and pytest do), else as given."""

from __future__ import annotations

import os
from pathlib import Path


def shown(path: str | Path) -> str:
    text = str(path)
    try:
        relative = os.path.relpath(text)
    except ValueError:  # another drive (Windows)
        return text
    if relative == ".":
        return str(Path(text).resolve())
    return text if relative.startswith("..") else relative
