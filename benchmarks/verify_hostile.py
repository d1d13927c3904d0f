"""Benchmark: `aeroexec verify` on hostile catalogs as large as the input cap allows.

Issue 23: a 14 MB catalog naming 1.5 million undefined lists took 119 s and 1.5 GB and
printed 1.5 million lines. Target: the input cap's worst case (`aeroexec.inputs
.TEXT_LIMIT`, 16 MB) in under 30 s of CPU and 500 MB of peak memory, time and memory
linear in the catalog's size.

Workloads, each a whole `python -m aeroexec verify FILE` in a fresh process (text
output, the default --max-findings):

* `distinct`: one behavior whose `incompatible_lists` names N distinct undefined lists
  (`l0, l1, ...`: the issue's catalog), at 1/4, 1/2 and all of the cap: one AX201 error
  per name;
* `repeated`: one undefined name repeated (`[x, x, x, ...]`), as many times as the YAML
  reader's node budget (`yamlnodes.DEFAULT_NODE_BUDGET`) admits: the most nodes any
  accepted catalog can hold.

Per run: CPU seconds of the child (user + system) and its peak resident memory
(`ru_maxrss` from `wait4`), medians of `--repeat` runs. Linearity: CPU and memory per
megabyte at the cap against at a quarter of it (1.0 is linear; the fixed cost of start-up
makes the smaller run dearer per MB, so a ratio <= 1.3 is called linear). The baseline of
the memory figure is the same process verifying the bundled 13-behavior catalog (start-up
and imports: what no catalog can go below).

    .venv/bin/python benchmarks/verify_hostile.py [--repeat 3] [--keep DIR]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from figures import Figure

from aeroexec.catalog.paths import DEFAULT_CATALOG
from aeroexec.catalog.yamlnodes import DEFAULT_NODE_BUDGET
from aeroexec.inputs import TEXT_LIMIT

TIME_TARGET_S = 30.0
MEMORY_TARGET_MB = 500.0
LINEAR = 1.3
HEAD = "behavior_descriptors:\n  - behavior: B\n    recurrent: yes\n    incompatible_lists: ["


def distinct_catalog(size: int) -> str:
    """Undefined list names `l0, l1, ...` filling `size` bytes (the issue's shape)."""
    parts = [HEAD]
    used = len(HEAD) + 2
    i = 0
    while True:
        name = f"l{i}, "
        if used + len(name) > size:
            break
        parts.append(name)
        used += len(name)
        i += 1
    return "".join(parts).rstrip(", ") + "]\n"


def repeated_catalog(nodes: int) -> str:
    """One undefined name, as many times as the node budget admits (the document, its
    mapping, the descriptor list and entry, their keys and scalars take a few)."""
    return HEAD + ",".join(["x"] * (nodes - 16)) + "]\n"


CASES = ("distinct 1/4 cap", "distinct 1/2 cap", "distinct at cap", "repeated at node budget")


def file_name(case: str) -> str:
    return case.replace(" ", "_").replace("/", "-") + ".yaml"


def generate(directory: Path) -> None:
    texts = {
        "distinct 1/4 cap": lambda: distinct_catalog(TEXT_LIMIT // 4),
        "distinct 1/2 cap": lambda: distinct_catalog(TEXT_LIMIT // 2),
        "distinct at cap": lambda: distinct_catalog(TEXT_LIMIT),
        "repeated at node budget": lambda: repeated_catalog(DEFAULT_NODE_BUDGET),
    }
    for case in CASES:
        (directory / file_name(case)).write_text(texts[case]())


def run_once(path: Path) -> tuple[float, float]:
    """(CPU seconds, peak resident MB) of one `python -m aeroexec verify path`."""
    child = subprocess.Popen(
        [sys.executable, "-m", "aeroexec", "verify", str(path)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    _, status, usage = os.wait4(child.pid, 0)
    child.returncode = os.waitstatus_to_exitcode(status)
    if child.returncode not in (0, 1):
        raise SystemExit(f"verify {path} exited {child.returncode}")
    return usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024


def measure(path: Path, repeat: int) -> tuple[float, float]:
    runs = [run_once(path) for _ in range(repeat)]
    return statistics.median(r[0] for r in runs), statistics.median(r[1] for r in runs)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--keep", type=Path, help="write the catalogs here and keep them")
    parser.add_argument("--generate", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.generate is not None:
        generate(args.generate)
        return 0
    directory = args.keep or Path(tempfile.mkdtemp(prefix="verify_hostile_"))
    directory.mkdir(parents=True, exist_ok=True)
    # Written by another process: a child's peak memory (ru_maxrss) counts the pages it
    # shared with this one before exec, so this one must never hold the catalogs.
    subprocess.run([sys.executable, __file__, "--generate", str(directory)], check=True)
    paths = {name: directory / file_name(name) for name in CASES}
    base_cpu, base_mb = measure(Path(DEFAULT_CATALOG), args.repeat)
    print(f"baseline (verify the bundled catalog): {base_cpu:.2f} s, {base_mb:.0f} MB")
    figures: list[Figure] = []
    measured: dict[str, tuple[float, float]] = {}
    for name, path in paths.items():
        cpu, mb = measure(path, args.repeat)
        measured[name] = (cpu, mb)
        size_mb = path.stat().st_size / 1e6
        print(f"{name}: {size_mb:.1f} MB of YAML, {cpu:.2f} s CPU, {mb:.0f} MB peak")
        if name == "distinct 1/4 cap" or name == "distinct 1/2 cap":
            continue
        figures.append(
            Figure(f"{name}: CPU", cpu, base_cpu, "bundled catalog", TIME_TARGET_S, kind="max")
        )
        figures.append(
            Figure(
                f"{name}: peak memory",
                mb,
                base_mb,
                "bundled catalog",
                MEMORY_TARGET_MB,
                unit=" MB",
                kind="max",
            )
        )
    small, large = paths["distinct 1/4 cap"], paths["distinct at cap"]
    scale = large.stat().st_size / small.stat().st_size
    (small_cpu, small_mb), (large_cpu, large_mb) = (
        measured["distinct 1/4 cap"],
        measured["distinct at cap"],
    )
    # Per MB at the cap against per MB at a quarter (memory above the start-up baseline).
    figures.append(
        Figure(
            "distinct: CPU growth per MB (cap vs 1/4)",
            large_cpu / scale,
            small_cpu,
            "1/4 cap",
            LINEAR,
        )
    )
    figures.append(
        Figure(
            "distinct: memory growth per MB (cap vs 1/4)",
            (large_mb - base_mb) / scale,
            small_mb - base_mb,
            "1/4 cap",
            LINEAR,
            unit=" MB",
        )
    )
    for figure in figures:
        print(figure.line())
    if args.keep is None:
        for path in paths.values():
            path.unlink()
        directory.rmdir()
    return 0 if all(f.ok for f in figures) else 1


if __name__ == "__main__":
    sys.exit(main())
