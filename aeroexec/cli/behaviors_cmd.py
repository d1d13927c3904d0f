"""`aeroexec behaviors`: every behavior implementation found, where it comes from, and
the catalog behaviors that have none."""

from __future__ import annotations

import json
from enum import Enum
from pathlib import Path
from typing import Any

import typer

from aeroexec.catalog import load_catalog
from aeroexec.catalog.paths import DEFAULT_CATALOG
from aeroexec.cli.app import app, guarded
from aeroexec.cli.options import (
    Color,
    apply_timeout,
    catalog_option,
    color_option,
    format_option,
    timeout_option,
    use_color,
)
from aeroexec.cli.project import (
    BehaviorsOption,
    DisablePluginOption,
    catalog_path,
    project,
    project_behaviors,
)
from aeroexec.cli.tables import print_table
from aeroexec.plugins import Implementation


class OutputFormat(str, Enum):
    text = "text"
    json = "json"


def _source(implementation: Implementation) -> str:
    origin = f" ({implementation.origin})" if not implementation.standard else ""
    replaced = [f"installed {implementation.shadows.origin}"] if implementation.shadows else []
    replaced += ["the standard library's"] if implementation.overrides else []
    replaces = f", replaces {' and '.join(replaced)}" if replaced else ""
    return f"{implementation.source}{origin}{replaces}"


def _as_dict(implementation: Implementation, in_catalog: bool) -> dict[str, Any]:
    mark = implementation.mark
    return {
        "behavior": implementation.name,
        "implementation": implementation.reference,
        "file": mark.file,
        "line": mark.line,
        "source": implementation.source,
        "origin": implementation.origin,
        "overrides_standard": implementation.overrides,
        "replaces_plugin": (
            implementation.shadows.reference if implementation.shadows is not None else None
        ),
        "in_catalog": in_catalog,
        "argument_names": (
            list(implementation.cls.argument_names)
            if implementation.cls.argument_names is not None
            else None
        ),
    }


@app.command("behaviors")
@guarded
def behaviors_command(
    catalog: Path | None = catalog_option(
        "Catalog to check (default: the project's, else the bundled default)."
    ),
    behaviors: BehaviorsOption = None,
    timeout: float | None = timeout_option(
        "Stop importing -b/--behaviors (and the project's) when it has run this long in "
        "wall-clock time: an error at its file:line, exit 2. Default: no limit."
    ),
    disable_plugin: DisablePluginOption = None,
    output_format: OutputFormat = format_option(
        OutputFormat, "text (a table) or json (every field, for machines)."
    ),
    color: Color = color_option(),
) -> None:
    """List every behavior implementation run, fly, replay and verify would use: the
    behavior, its class (module:Class), its file and the source that provided it; then
    the catalog's behaviors that have no implementation.

    \b
    Examples:
      aeroexec behaviors
      aeroexec behaviors -b mybehaviors --catalog my-catalog.yaml --format json

    Exit codes: 0 every catalog behavior has an implementation; 1 some have none;
    2 the catalog, the configuration or a behavior module could not be used.
    """
    apply_timeout(timeout)
    settings = project()
    found = project_behaviors(behaviors, settings, disable_plugin)
    chosen = catalog_path(catalog, settings, DEFAULT_CATALOG)
    loaded = load_catalog(chosen)
    missing = found.missing(loaded)
    implementations = sorted(found.implementations.values(), key=lambda i: i.name)
    if output_format is OutputFormat.json:
        document = {
            "catalog": str(chosen),
            "implementations": [_as_dict(i, i.name in loaded.behaviors) for i in implementations],
            "unimplemented": list(missing),
            "searched": list(found.searched),
        }
        typer.echo(json.dumps(document, indent=2))
    else:
        rows = []
        for implementation in implementations:
            mark = implementation.mark
            where = f"{mark.file}:{mark.line}" if mark.line else mark.file
            used = "" if implementation.name in loaded.behaviors else "(not in the catalog)"
            rows.append(
                [
                    implementation.name,
                    implementation.reference,
                    where,
                    _source(implementation),
                    used,
                ]
            )
        print_table(
            f"Behavior implementations ({len(rows)})",
            ["behavior", "implementation", "file", "source", ""],
            rows,
            styled=use_color(color),
        )
        typer.echo(f"looked in: {'; '.join(found.searched)}")
        if missing:
            typer.echo(
                f"{chosen}: {len(missing)} behavior(s) without an implementation: "
                f"{', '.join(missing)}"
            )
        else:
            typer.echo(f"{chosen}: every behavior has an implementation")
    if missing:
        raise typer.Exit(1)
