"""`aeroexec import BAG -o FILE`: a ROS 1 bag to an aeroexec recording (MCAP)."""

from __future__ import annotations

import json
from enum import Enum
from typing import Annotated

import typer

from aeroexec.bags.importer import import_bag
from aeroexec.cli.app import app, guarded
from aeroexec.cli.options import choices, format_option, output_option
from aeroexec.progress import progress_bar


class ImportFormat(str, Enum):
    text = "text"
    json = "json"


class Compression(str, Enum):
    lz4 = "lz4"
    zstd = "zstd"
    none = "none"


@app.command("import")
@guarded
def import_(
    bag: Annotated[
        str,
        typer.Argument(
            metavar="BAG", help="A ROS 1 bag (v2.0; plain, bz2 or lz4 chunks).", show_default=False
        ),
    ],
    output: str = output_option("The recording (MCAP) to write.", required=True),
    mapping: Annotated[
        str | None,
        typer.Option(
            "--mapping",
            metavar="FILE",
            help="Topic mapping (YAML). Default: Aerostack's topic names (see docs/bags.md).",
            show_default=False,
        ),
    ] = None,
    drone: Annotated[
        str | None,
        typer.Option(
            "--drone",
            metavar="NAME",
            help="The drone's namespace: {drone} in the mapping (default: drone1).",
            show_default=False,
        ),
    ] = None,
    compression: Annotated[
        Compression,
        typer.Option(
            "--compression",
            metavar=choices(Compression),
            help="MCAP chunk compression.",
            show_default=True,
        ),
    ] = Compression.lz4,
    output_format: ImportFormat = format_option(
        ImportFormat, "text for people, json for machines."
    ),
) -> None:
    """Convert a ROS 1 bag into an aeroexec recording (MCAP), losing nothing.

    Every message of the bag is copied byte for byte to a raw ros1 channel named
    /ros1<topic> (readable by Foxglove and `mcap`). The topics the mapping names become
    aeroexec channels under /<drone>/: behavior_event, list_of_active_behaviors,
    list_of_active_capabilities, beliefs, process_state, vehicle/state. Commands the bag
    does not hold (2017 Aerostack sent them as service calls) are reconstructed from the
    changes of the active-behavior list and marked "reconstructed": true. Log times are
    the bag's.

    \b
    Examples:
      aeroexec import flight.bag -o flight.mcap
      aeroexec import flight.bag -o flight.mcap --mapping map.yaml --drone drone2
      aeroexec replay flight.bag --catalog catalog/aerostack-2017.yaml

    Exit codes: 0 written; 2 the bag or the mapping could not be read, or the recording
    not written (one line on stderr; no partial file is left).
    """
    report = import_bag(
        bag,
        output,
        mapping=mapping,
        drone=drone,
        compression=compression.value,
        progress=lambda name, total: progress_bar(f"importing {name}", total),
    )
    if output_format is ImportFormat.json:
        typer.echo(json.dumps(report.as_dict(), indent=2))
    else:
        typer.echo(report.summary())
