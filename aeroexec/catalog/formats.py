"""Read a catalog of any generation Aerostack used, for the verifier.

The executive runs behavior catalogs only (`aeroexec.catalog.loader`); the verifier also
reads the 2020-2021 task catalogs (`aeroexec.catalog.task_loader`), into their own model.
The YAML is parsed once and the format decided from its top-level keys.
"""

from __future__ import annotations

from pathlib import Path

from aeroexec.catalog.loader import parse_root, read_catalog_text
from aeroexec.catalog.model import Catalog
from aeroexec.catalog.task_loader import is_task_catalog, read_task_catalog
from aeroexec.catalog.tasks import TaskCatalog
from aeroexec.catalog.yamlnodes import YNode, load_yaml

AnyCatalog = Catalog | TaskCatalog


def parse_any_catalog(text: str, file: str = "<string>") -> AnyCatalog:
    return catalog_from_root(load_yaml(text, file), text, file)


def catalog_from_root(root: YNode | None, text: str, file: str) -> AnyCatalog:
    """The catalog of an already parsed YAML document (either generation)."""
    if root is not None and root.is_map and is_task_catalog(root):
        return read_task_catalog(root, file, text)
    return parse_root(root, text, file)


def read_any_catalog(path: str | Path) -> AnyCatalog:
    """Leniently, like `read_catalog`; `CatalogError` only for unreadable input."""
    text, file = read_catalog_text(path)
    return parse_any_catalog(text, file)
