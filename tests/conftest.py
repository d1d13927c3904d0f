"""Shared fixtures. Keep this small: module-specific helpers live in their test module."""

from __future__ import annotations

import os
from collections.abc import Iterator

import pytest
from hypothesis import settings
from live_helpers import AeroexecProcess

from aeroexec.catalog import THESIS_CATALOG, Catalog, load_catalog

# Every property-based test draws the same examples on every run (and keeps no example
# database in the working tree): CI cannot turn red by chance. A deeper random search
# is one environment variable away: AEROEXEC_HYPOTHESIS_RANDOM=1.
settings.register_profile("deterministic", derandomize=True, database=None)
settings.register_profile("random")
settings.load_profile("random" if os.environ.get("AEROEXEC_HYPOTHESIS_RANDOM") else "deterministic")


@pytest.fixture(scope="session")
def thesis_catalog() -> Catalog:
    """The thesis' Appendix A catalog, loaded strictly (read-only: Catalog is frozen)."""
    return load_catalog(THESIS_CATALOG)


@pytest.fixture
def procs() -> Iterator[list[AeroexecProcess]]:
    """`aeroexec` subprocesses a test starts (the live tests): killed after it, whatever
    it asserted. A module with processes of another kind defines its own."""
    started: list[AeroexecProcess] = []
    yield started
    for proc in started:
        proc.kill()
