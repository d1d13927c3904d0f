"""`aeroexec import BAG -o FILE`: a ROS 1 or ROS 2 bag to an aeroexec recording (MCAP)."""

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
            metavar="BAG",
            help="A ROS 1 bag (v2.0; plain, bz2 or lz4 chunks) or a ROS 2 bag (a rosbag2 "
            "directory, a .mcap or a .db3).",
            show_default=False,
        ),
    ],
    output: str = output_option("The recording (MCAP) to write.", required=True),
    mapping: Annotated[
        str | None,
        typer.Option(
            "--mapping",
            metavar="FILE",
            help="Topic mapping (YAML). Default: Aerostack's topic names for a ROS 1 bag, "
            "Aerostack2's for a ROS 2 one (see docs/bags.md).",
            show_default=False,
        ),
    ] = None,
    drone: Annotated[
        str | None,
        typer.Option(
            "--drone",
            metavar="NAME",
            help="The drone's namespace: {drone} in the mapping (default: the mapping's, "
            "drone1 for Aerostack, drone0 for Aerostack2).",
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
    types_dir: Annotated[
        str | None,
        typer.Option(
            "--types",
            metavar="DIR",
            help="ROS 2 message definitions for a bag without them: a folder of packages, "
            "each with msg, srv or action folders (.msg, .srv, .action files).",
            show_default=False,
        ),
    ] = None,
    output_format: ImportFormat = format_option(
        ImportFormat, "text for people, json for machines."
    ),
) -> None:
    """Convert a ROS 1 or ROS 2 bag into an aeroexec recording (MCAP), losing nothing.

    Every message of the bag is copied byte for byte to a raw channel named /ros1<topic>
    (ROS 1) or /ros2<topic> (ROS 2, cdr) that Foxglove and `mcap` decode. The topics the
    mapping names become aeroexec channels under /<drone>/: behavior_event,
    list_of_active_behaviors, list_of_active_capabilities, beliefs, process_state,
    vehicle/state; a ROS 2 bag's recorded service calls become service-call channels.
    Commands the bag does not hold (Aerostack sent them as service calls, Aerostack2 as
    action goals) are reconstructed from the active-behavior list (Aerostack2: the
    behavior status) and marked "reconstructed": true. Log times are the bag's.

    \b
    Examples:
      aeroexec import flight.bag -o flight.mcap
      aeroexec import flight.bag -o flight.mcap --mapping map.yaml --drone drone2
      aeroexec import rosbag2_2025_11_24/ -o flight.mcap --types my_msgs/
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
        types_dir=types_dir,
        progress=lambda name, total: progress_bar(f"importing {name}", total),
    )
    if output_format is ImportFormat.json:
        typer.echo(json.dumps(report.as_dict(), indent=2))
    else:
        typer.echo(report.summary())
