"""The behavior catalog: model, loader with `file:line:col` marks, argument checks."""

from aeroexec.catalog.arguments import ArgumentCheck, check_arguments
from aeroexec.catalog.loader import load_catalog, parse_catalog, read_catalog, strict
from aeroexec.catalog.model import (
    ArgumentKind,
    ArgumentSpec,
    BehaviorDescriptor,
    BehaviorList,
    CapabilityDescriptor,
    Catalog,
    Diagnostic,
    Severity,
)
from aeroexec.catalog.paths import DEFAULT_CATALOG, THESIS_CATALOG

__all__ = [
    "DEFAULT_CATALOG",
    "THESIS_CATALOG",
    "ArgumentCheck",
    "ArgumentKind",
    "ArgumentSpec",
    "BehaviorDescriptor",
    "BehaviorList",
    "CapabilityDescriptor",
    "Catalog",
    "Diagnostic",
    "Severity",
    "check_arguments",
    "load_catalog",
    "parse_catalog",
    "read_catalog",
    "strict",
]
