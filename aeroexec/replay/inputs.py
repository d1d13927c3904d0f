"""Which recordings a command line names: files, directories (every `*.mcap`, ROS 1
`*.bag`, ROS 2 `*.db3` and rosbag2 directory inside, sorted) and glob patterns (sorted
matches, rosbag2 directories included), in the order given; the same for URLs
(`s3://bucket/flights/`, through fsspec: aeroexec.replay.remote, files only). A rosbag2
directory (one with its `metadata.yaml`) is one ROS 2 bag, never a folder of
recordings: its storage files are not inputs of their own."""

from __future__ import annotations

import os
from dataclasses import dataclass

from aeroexec.inputs import directory_files, glob_files, has_magic, is_directory
from aeroexec.replay.remote import expand_url, is_url

#: The files a directory contributes (a `.mcap` is an aeroexec recording or a ROS 2 bag).
SUFFIXES = (".mcap", ".bag", ".db3")
#: What makes a directory one rosbag2 bag rather than a folder of recordings.
ROSBAG2_METADATA = "metadata.yaml"
EMPTY_DIRECTORY = (
    "no *.mcap recordings in this directory (nor ROS bags: *.bag, *.db3, rosbag2 directories)"
)


def is_rosbag2_directory(path: str) -> bool:
    """A directory with a `metadata.yaml`: one ROS 2 bag."""
    return is_directory(path) and os.path.isfile(os.path.join(path, ROSBAG2_METADATA))


@dataclass(frozen=True, slots=True)
class Input:
    """A recording to replay, or (with `error`) an argument that names none."""

    path: str
    error: str | None = None


def expand_inputs(arguments: list[str]) -> list[Input]:
    """The recordings `arguments` name, in order. A directory that cannot be listed (the
    one given, or one under a `**` pattern) and a match that is a symlink loop are
    inputs with an error, like a pattern that matches nothing: reported, never skipped
    in silence (`aeroexec.inputs.glob_files`)."""
    out: list[Input] = []
    for argument in arguments:
        if is_url(argument):
            out.extend(
                Input(url, error) for url, error in expand_url(argument, SUFFIXES, EMPTY_DIRECTORY)
            )
            continue
        if is_rosbag2_directory(argument):
            out.append(Input(argument))  # a ROS 2 bag: one recording, imported first
            continue
        if is_directory(argument):
            found = directory_files(argument, SUFFIXES, is_rosbag2_directory)
            if not found.files and not found.unreadable:
                out.append(Input(argument, EMPTY_DIRECTORY))
        elif not os.path.lexists(argument) and has_magic(argument):
            found = glob_files(argument, is_rosbag2_directory)
            if not found.files and not found.unreadable:
                out.append(Input(argument, "no recordings match this pattern"))
        else:
            out.append(Input(argument))
            continue
        out.extend(Input(u.path, u.problem) for u in found.unreadable)
        out.extend(Input(p) for p in found.files)
    return out
