"""`--shard K/N`: a deterministic slice of a corpus, for CI matrices.

Each recording belongs to the shard its path hashes to (SHA-256 of the path as the
report names it, modulo N), not to the shard its position falls in: adding or removing a
recording moves no other recording to another shard, so a shard's history stays
comparable from one pull request to the next. Shards are balanced statistically (a few
percent apart on hundreds of recordings), not exactly.

A shard's JSON report carries a `shard` block that `aeroexec report merge` needs to put
the shards back together: which shard it is, where each of its recordings stood in the
whole corpus, and a fingerprint of that corpus (so shards of different checkouts are
refused instead of merged into a report that looks whole).
"""

from __future__ import annotations

import hashlib
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import PurePath
from typing import Any

from aeroexec.errors import AeroexecError
from aeroexec.replay.engine import ReplayOptions

_SHARD = re.compile(r"\s*(\d+)\s*/\s*(\d+)\s*")
#: The version of the `shard` block; `report merge` refuses others.
SHARD_FORMAT = 1


@dataclass(frozen=True, slots=True)
class Shard:
    """Shard `index` (1-based, as CI matrices count) of `count`."""

    index: int
    count: int

    def __str__(self) -> str:
        return f"{self.index}/{self.count}"

    def holds(self, name: str) -> bool:
        return shard_of(name, self.count) == self.index


def parse_shard(text: str) -> Shard:
    """`"2/4"` -> Shard(2, 4); anything else is an `AeroexecError` saying what is wanted."""
    match = _SHARD.fullmatch(text)
    if match is None:
        raise AeroexecError(f"--shard: expected K/N (e.g. 2/4), got {text!r}")
    index, count = int(match[1]), int(match[2])
    if count < 1 or not 1 <= index <= count:
        raise AeroexecError(f"--shard: K/N needs 1 <= K <= N, got {text!r}")
    return Shard(index, count)


def shard_key(name: str) -> str:
    """The string hashed for `name`: a path with forward slashes whatever the OS (a URL
    as it is), so every runner of a matrix agrees."""
    if "://" in name:
        return name
    return PurePath(name).as_posix()


def shard_of(name: str, count: int) -> int:
    """The 1-based shard of `count` that the recording `name` belongs to."""
    digest = hashlib.sha256(shard_key(name).encode("utf-8")).digest()
    return int.from_bytes(digest[:8], "big") % count + 1


def corpus_fingerprint(names: Sequence[str]) -> str:
    """What identifies the whole corpus (every input, in order): shards of one run agree."""
    digest = hashlib.sha256()
    for name in names:
        digest.update(shard_key(name).encode("utf-8") + b"\n")
    return digest.hexdigest()[:16]


@dataclass(frozen=True, slots=True)
class ShardSlice:
    """The positions (in the whole corpus) of the inputs a shard replays."""

    shard: Shard
    positions: tuple[int, ...]
    total: int
    corpus: str
    #: What the replay compared with (catalog, mode, tolerances): shards must agree.
    settings: dict[str, Any]

    def block(self) -> dict[str, Any]:
        """The `shard` block of the shard's JSON report."""
        return {
            "format": SHARD_FORMAT,
            "shard": str(self.shard),
            "index": self.shard.index,
            "count": self.shard.count,
            "corpus": self.corpus,
            "total": self.total,
            "positions": list(self.positions),
            "settings": self.settings,
        }


def settings_of(options: ReplayOptions) -> dict[str, Any]:
    """What the shards of one run must agree on (JSON values): the catalog, the mode,
    the tolerances and the property files (`--spec`). (Outputs are per shard.)"""
    settings = {
        "catalog": options.catalog,
        "mode": options.mode.value if options.mode is not None else None,
        "tolerance_s": options.tolerance.time_s,
        "position_tolerance_m": options.tolerance.position_m,
    }
    if options.properties:  # --spec: the same property files, the same texts
        digest = hashlib.sha256(repr(options.properties).encode()).hexdigest()[:16]
        settings["properties"] = [*(name for name, _ in options.properties), digest]
    return settings


def slice_for(names: Sequence[str], shard: Shard, settings: dict[str, Any]) -> ShardSlice:
    """Which of `names` (the whole corpus, in report order) `shard` replays."""
    positions = tuple(i for i, name in enumerate(names) if shard.holds(name))
    return ShardSlice(shard, positions, len(names), corpus_fingerprint(names), settings)
