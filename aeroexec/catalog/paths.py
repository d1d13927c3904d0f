"""Where the catalogs shipped with aeroexec live (inside the package, so installs find them)."""

from __future__ import annotations

from pathlib import Path

DATA_DIR = Path(__file__).resolve().parent.parent / "data"
DEFAULT_CATALOG = DATA_DIR / "catalog" / "default.yaml"
THESIS_CATALOG = DATA_DIR / "catalog" / "aerostack-2017.yaml"
