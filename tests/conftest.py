"""Shared fixtures. Keep this small: module-specific helpers live in their test module."""

from __future__ import annotations

from pathlib import Path

import pytest

from aeroexec.catalog import THESIS_CATALOG, Catalog, load_catalog

FIXTURES = Path(__file__).resolve().parent / "fixtures"


@pytest.fixture(scope="session")
def fixtures_dir() -> Path:
    return FIXTURES


@pytest.fixture(scope="session")
def thesis_catalog() -> Catalog:
    """The thesis' Appendix A catalog, loaded strictly (read-only: Catalog is frozen)."""
    return load_catalog(THESIS_CATALOG)
