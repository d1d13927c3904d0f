"""What the commands that run behaviors share: the project configuration and the
`--behaviors` / `--allow-unimplemented` options.

An option given on the command line wins over the project configuration
(`[tool.aeroexec]` in the nearest pyproject.toml, or aeroexec.toml), which wins over
aeroexec's defaults.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, TypeVar

import typer

from aeroexec.config import ProjectConfig, load_config
from aeroexec.plugins import BehaviorSet, BehaviorSources, discover, sources_for

BehaviorsOption = Annotated[
    list[str] | None,
    typer.Option(
        "--behaviors",
        "-b",
        metavar="MODULE_OR_FILE",
        help="Your behaviors: a module, a package or a .py file (repeatable); added to the "
        "project's [tool.aeroexec] behaviors, installed 'aeroexec.behaviors' entry points "
        "and the standard library.",
        show_default=False,
    ),
]

AllowUnimplementedOption = Annotated[
    bool,
    typer.Option(
        "--allow-unimplemented",
        help="Run catalog behaviors that have no implementation as stand-ins that succeed "
        "after 1 s (announced, and marked in the recording) instead of refusing.",
    ),
]

T = TypeVar("T")


def project() -> ProjectConfig:
    """The project configuration found from the working directory upward."""
    return load_config()


def behavior_sources(behaviors: list[str] | None, config: ProjectConfig) -> BehaviorSources:
    return sources_for(behaviors or (), config)


def project_behaviors(behaviors: list[str] | None, config: ProjectConfig) -> BehaviorSet:
    """Every behavior the command line, the project and the installed packages provide,
    then the standard library (`BehaviorError`, one line, for a bad one)."""
    return discover(behavior_sources(behaviors, config))


def first(given: T | None, configured: T | None, default: T) -> T:
    """The command line's value, else the project's, else aeroexec's."""
    if given is not None:
        return given
    if configured is not None:
        return configured
    return default


def catalog_path(given: Path | None, config: ProjectConfig, default: Path) -> Path:
    return first(given, config.catalog, default)
