"""A developer's own behaviors: where they come from, and which code ran.

    sources = sources_for(command_line=["mybehaviors"], config=load_config())
    behaviors = discover(sources)          # BehaviorError (one line, file:line) if unusable
    behaviors = behaviors.for_catalog(catalog)   # BehaviorError listing what has no code
    simulate(SessionConfig(mission, behaviors=behaviors))

Sources, in order of precedence: `--behaviors` and the project configuration's
`behaviors` (the project's own), installed entry points (`aeroexec.behaviors`, the
plugins: all off with `AEROEXEC_DISABLE_PLUGIN_AUTOLOAD=1`, one with `--disable-plugin` or
the configuration's `disable_plugins`), the standard library (`discovery`). `manifest` says
which code implemented each behavior, for recordings and replay's "code changed".
"""

from __future__ import annotations

import os
from collections.abc import Sequence

from aeroexec.config import ProjectConfig
from aeroexec.plugins.discovery import (
    DISABLE_AUTOLOAD,
    ENTRY_POINT_GROUP,
    BehaviorSet,
    BehaviorSources,
    Implementation,
    autoload_enabled,
    behaviors_in,
    discover,
    discovered,
    standard_set,
)
from aeroexec.plugins.manifest import CodeEntry, CodeManifest, code_changes, code_manifest


def sources_for(
    command_line: Sequence[str] = (),
    config: ProjectConfig | None = None,
    disabled_plugins: Sequence[str] = (),
) -> BehaviorSources:
    """Where a command looks: its `--behaviors` values (relative to the working
    directory), then the configuration's (relative to its file), then entry points
    (unless `AEROEXEC_DISABLE_PLUGIN_AUTOLOAD` is set), but not those of the plugins
    `--disable-plugin` and the configuration's `disable_plugins` name."""
    configured = config.disable_plugins if config is not None else None
    autoload = autoload_enabled()
    return BehaviorSources(
        command_line=tuple(command_line),
        command_line_root=os.getcwd(),
        config=config.behaviors if config is not None else None,
        config_file=str(config.path) if config is not None and config.path else None,
        config_label=config.label if config is not None else "",
        entry_points=autoload,
        entry_points_off="" if autoload else f"{DISABLE_AUTOLOAD} is set",
        disabled_plugins=(*disabled_plugins, *(configured or ())),
    )


__all__ = [
    "DISABLE_AUTOLOAD",
    "ENTRY_POINT_GROUP",
    "BehaviorSet",
    "BehaviorSources",
    "CodeEntry",
    "CodeManifest",
    "Implementation",
    "autoload_enabled",
    "behaviors_in",
    "code_changes",
    "code_manifest",
    "discover",
    "discovered",
    "sources_for",
    "standard_set",
]
