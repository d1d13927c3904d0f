"""Which recordings a command line names: files, directories (every `*.mcap` and ROS 1
`*.bag` inside, sorted; a rosbag2 directory, with its `metadata.yaml`, is one ROS 2
bag) and glob patterns (sorted matches), in the order given; the same for URLs
(`s3://bucket/flights/`, through fsspec: aeroexec.replay.remote)."""

from __future__ import annotations

import glob
from dataclasses import dataclass
from pathlib import Path

from aeroexec.replay.remote import expand_url, is_url

_GLOB_CHARS = frozenset("*?[")
#: What a directory contributes.
SUFFIXES = (".mcap", ".bag")
#: What makes a directory one rosbag2 bag rather than a folder of recordings.
ROSBAG2_METADATA = "metadata.yaml"
EMPTY_DIRECTORY = "no *.mcap recordings in this directory (nor ROS 1 *.bag)"


@dataclass(frozen=True, slots=True)
class Input:
    """A recording to replay, or (with `error`) an argument that names none."""

    path: str
    error: str | None = None


def expand_inputs(arguments: list[str]) -> list[Input]:
    out: list[Input] = []
    for argument in arguments:
        if is_url(argument):
            out.extend(
                Input(url, error) for url, error in expand_url(argument, SUFFIXES, EMPTY_DIRECTORY)
            )
            continue
        path = Path(argument)
        if path.is_dir() and (path / ROSBAG2_METADATA).is_file():
            out.append(Input(argument))  # a ROS 2 bag: one recording, imported first
        elif path.is_dir():
            found = sorted(
                str(p) for p in path.iterdir() if p.suffix.lower() in SUFFIXES and p.is_file()
            )
            if not found:
                out.append(Input(argument, EMPTY_DIRECTORY))
            out.extend(Input(p) for p in found)
        elif not path.exists() and _GLOB_CHARS & set(argument):
            matches = sorted(m for m in glob.glob(argument, recursive=True) if Path(m).is_file())
            if not matches:
                out.append(Input(argument, "no recordings match this pattern"))
            out.extend(Input(m) for m in matches)
        else:
            out.append(Input(argument))
    return out
