"""`aeroexec info` and `aeroexec recover`: look at and repair MCAP recordings."""

from __future__ import annotations

import json
from enum import Enum
from typing import Annotated, Any

import typer

from aeroexec.bags.info import PROFILES as BAG_PROFILES
from aeroexec.bags.info import bag_info
from aeroexec.bags.source import is_bag
from aeroexec.cli.app import app, error_line, guarded
from aeroexec.cli.options import format_option, output_option
from aeroexec.recording.info import recording_info
from aeroexec.recording.recover import recover as recover_file

#: Text output lists at most this many behavior activations (json lists all).
MAX_BEHAVIOR_LINES = 40


class InfoFormat(str, Enum):
    text = "text"
    json = "json"


def _format_option() -> Any:
    return format_option(InfoFormat, "text for people, json for machines.")


@app.command("info")
@guarded
def info(
    recording: Annotated[
        str,
        typer.Argument(
            metavar="REC",
            help="An MCAP file (aeroexec or any other profile), a ROS 1 bag or a ROS 2 "
            "bag (a rosbag2 directory or a .db3).",
            show_default=False,
        ),
    ],
    output_format: InfoFormat = _format_option(),
) -> None:
    """Summarize a recording: duration, channels and message counts, behaviors and
    their outcomes, metadata, attachments, and whether the file is complete.

    Reads the file in one streaming pass without needing its footer, so it also works on
    a recording whose writer was killed (it says the file is incomplete and how far it
    could be read; `aeroexec recover` makes a complete copy). Files of other tools (e.g.
    ROS 2 bags in MCAP) show their channels and counts.

    \b
    Examples:
      aeroexec info flight.mcap
      aeroexec info flight.mcap --format json | jq '.channels'

    Exit codes: 0 read (completely or up to damage, which is reported on stderr);
    2 nothing could be read (missing, empty, not MCAP): one line on stderr.
    """
    report = bag_info(recording) if is_bag(recording) else recording_info(recording)
    if output_format is InfoFormat.json:
        typer.echo(report.to_json())
    else:
        typer.echo(_limit_behaviors(report.to_text(), len(report.behaviors)))
    if report.damages:
        error_line(f"{report.file}: warning: damaged recording: {report.problem}")
    elif not report.complete and report.profile in BAG_PROFILES.values():
        error_line(f"{report.file}: warning: damaged bag: {report.problem}")
    elif not report.complete:
        error_line(
            f"{report.file}: warning: incomplete recording: {report.problem}; "
            f"{report.messages} messages read (run `aeroexec recover`)"
        )


def _limit_behaviors(text: str, count: int) -> str:
    if count <= MAX_BEHAVIOR_LINES:
        return text
    lines = text.split("\n")
    start = lines.index("behaviors:") + 1
    cut = lines[start + MAX_BEHAVIOR_LINES : start + count]
    more = f"  ... {len(cut)} more activations (--format json lists all)"
    return "\n".join([*lines[: start + MAX_BEHAVIOR_LINES], more, *lines[start + count :]])


@app.command("recover")
@guarded
def recover(
    broken: Annotated[
        str,
        typer.Argument(
            metavar="REC", help="The damaged or unfinished MCAP file.", show_default=False
        ),
    ],
    output: str = output_option("Where to write the complete copy.", required=True),
    output_format: InfoFormat = _format_option(),
) -> None:
    """Write a complete MCAP file with every message that can be read from REC.

    A recording whose process was killed has no footer or summary, and one damaged in
    transfer may end in garbage. recover reads REC record by record up to the first
    damage and writes all schemas, channels, messages, attachments and metadata before it
    to the -o file, with a proper summary and footer (readable by Foxglove and `mcap`). An
    aeroexec recording loses at most its last flush interval (100 messages or 0.5 s).

    \b
    Example:
      aeroexec recover crashed.mcap -o fixed.mcap && aeroexec info fixed.mcap

    Exit codes: 0 written; 2 REC could not be read at all, or the copy not written.
    """
    report = recover_file(broken, output)
    if output_format is InfoFormat.json:
        typer.echo(
            json.dumps(
                {
                    "source": report.source,
                    "target": report.target,
                    "messages": report.messages,
                    "channels": report.channels,
                    "attachments": report.attachments,
                    "metadata": report.metadata,
                    "source_complete": report.source_complete,
                    "stopped_at": report.stopped_at,
                    "problem": report.problem,
                    "damages": [d.as_dict() for d in report.damages],
                    "expected_messages": report.expected_messages,
                },
                indent=2,
            )
        )
    else:
        typer.echo(report.summary())
        for damage in report.damages:
            typer.echo(f"{report.source}: not copied: {damage.describe()}")
        if report.cut:
            typer.echo(f"{report.source}: stopped reading: {report.cut}")
