"""`aeroexec catalog ...`: look at a behavior catalog the way the executive reads it."""

from __future__ import annotations

import json
from enum import Enum
from typing import Annotated

import typer
from rich.console import Console

from aeroexec.catalog import load_catalog
from aeroexec.catalog.show import catalog_to_json, render_plain, render_rich
from aeroexec.cli.app import app, guarded
from aeroexec.cli.command import Typer
from aeroexec.cli.options import Color, color_option, format_option, use_color

catalog_app = Typer(
    help=(
        "Inspect behavior catalogs (the YAML file of behavior_descriptors, behavior_lists "
        "and capability_descriptors that the behavior specialist reads).\n\n"
        "\b\n"
        "Example:\n"
        "  aeroexec catalog show catalog/aerostack-2017.yaml"
    ),
    no_args_is_help=True,
    rich_markup_mode=None,
)
app.add_typer(catalog_app, name="catalog")


class OutputFormat(str, Enum):
    text = "text"
    json = "json"


@catalog_app.command("show")
@guarded
def show(
    file: Annotated[
        str,
        typer.Argument(
            metavar="CATALOG",
            help="The catalog YAML file (thesis Appendix A or Aerostack 2.x dialect).",
            show_default=False,
        ),
    ],
    output_format: OutputFormat = format_option(
        OutputFormat,
        "text: for people (styled per --color, else plain grep-able lines); json: one "
        "JSON object for machines.",
    ),
    color: Color = color_option(),
) -> None:
    """Show a behavior catalog: what the executive will do with it.

    Loads CATALOG strictly, as the executive does, and prints every behavior (timeout,
    recurrent flag, incompatible lists and the behaviors they preempt, capabilities,
    arguments with their allowed values), every list with its members, every capability
    (processes, conflicts, required capabilities, active by default), the dialect read,
    then the loader's diagnostics as `file:line:col: severity CODE message`. Those are
    the loader's only: `aeroexec verify CATALOG` is the check (its rules find dangling
    references, capability conflicts, start-order cycles...).

    \b
    Examples:
      aeroexec catalog show catalog/aerostack-2017.yaml
      aeroexec catalog show catalog/default.yaml | grep -A6 '^  GO_TO_POINT '
      aeroexec catalog show my_catalog.yaml -f json | jq '.behaviors[].name'

    Exit codes: 0 shown; 2 the catalog could not be loaded (one line on stderr,
    `file:line:col: error: ...`).
    """
    # A plain `str` argument, not `typer.Argument(exists=True)`: a missing file must get
    # the same one-line `file: error: ...` as every other unreadable catalog.
    catalog = load_catalog(file)
    if output_format is OutputFormat.json:
        typer.echo(json.dumps(catalog_to_json(catalog), indent=2, allow_nan=False))
    elif use_color(color):
        render_rich(catalog, Console(force_terminal=True))
    else:
        typer.echo(render_plain(catalog), nl=False)
