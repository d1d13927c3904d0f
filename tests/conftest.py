"""Shared fixtures. Keep this small: module-specific helpers live in their test module."""

from __future__ import annotations

import pytest

from aeroexec.catalog import THESIS_CATALOG, Catalog, load_catalog


@pytest.fixture(scope="session")
def thesis_catalog() -> Catalog:
    """The thesis' Appendix A catalog, loaded strictly (read-only: Catalog is frozen)."""
    return load_catalog(THESIS_CATALOG)
