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

from aeroexec.cli.app import say
from aeroexec.config import ProjectConfig, load_config
from aeroexec.plugins import (
    DISABLE_AUTOLOAD,
    BehaviorSet,
    BehaviorSources,
    discover,
    sources_for,
)

BehaviorsOption = Annotated[
    list[str] | None,
    typer.Option(
        "--behaviors",
        "-b",
        metavar="MODULE_OR_FILE",
        help="Your behaviors: a module, a package or a .py file (repeatable); added to the "
        "project's [tool.aeroexec] behaviors, before installed plugins ('aeroexec.behaviors' "
        "entry points) and the standard library, whose behaviors of the same name they "
        "replace.",
        show_default=False,
    ),
]

DisablePluginOption = Annotated[
    list[str] | None,
    typer.Option(
        "--disable-plugin",
        metavar="NAME",
        help="Do not load this installed plugin (its distribution name, as pip lists it; "
        f"repeatable); {DISABLE_AUTOLOAD}=1 loads none.",
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


def behavior_sources(
    behaviors: list[str] | None, config: ProjectConfig, disabled: list[str] | None = None
) -> BehaviorSources:
    return sources_for(behaviors or (), config, disabled or ())


def discovered_behaviors(sources: BehaviorSources) -> BehaviorSet:
    """`discover(sources)`, with a note on stderr for each installed plugin's behavior
    that the project's own replaces."""
    found = discover(sources)
    for note in found.notes():
        say("note", note)
    return found


def project_behaviors(
    behaviors: list[str] | None, config: ProjectConfig, disabled: list[str] | None = None
) -> BehaviorSet:
    """Every behavior the command line, the project and the installed plugins provide,
    then the standard library (`BehaviorError`, one line, for a bad one)."""
    return discovered_behaviors(behavior_sources(behaviors, config, disabled))


def first(given: T | None, configured: T | None, default: T) -> T:
    """The command line's value, else the project's, else aeroexec's."""
    if given is not None:
        return given
    if configured is not None:
        return configured
    return default


def catalog_path(given: Path | None, config: ProjectConfig, default: Path) -> Path:
    return first(given, config.catalog, default)
