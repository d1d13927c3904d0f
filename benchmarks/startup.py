"""Benchmark: what starting `aeroexec` costs a user (issue 17).

Each figure is the CPU time (user + system) of a fresh `python -m aeroexec ...` process,
the median of --repeat runs interleaved with the baseline, `python -c pass` (the
interpreter and its site packages: what no Python command line can go below):

* `aeroexec --version` and `aeroexec --help`: target <= 0.15 s;
* `aeroexec verify catalog/default.yaml` (a small catalog, every rule): target <= 0.3 s.

Prints one line per figure (figure, baseline, ratio, target); exits 1 when one is missed.

    .venv/bin/python benchmarks/startup.py [--repeat 15]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from figures import Figure, child_cpu, interleaved

ROOT = Path(__file__).resolve().parent.parent
CASES = {
    "aeroexec --version": (["--version"], 0.15),
    "aeroexec --help": (["--help"], 0.15),
    "aeroexec verify catalog/default.yaml": (["verify", "catalog/default.yaml"], 0.3),
}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument(
        "--root",
        type=Path,
        default=ROOT,
        help="the checkout to measure (its aeroexec package is the one `python -m` finds)",
    )
    args = parser.parse_args(argv)
    python = sys.executable
    root = str(args.root)
    actions = {"python -c pass": lambda: child_cpu([python, "-c", "pass"], root)}
    for name, (arguments, _) in CASES.items():
        command = [python, "-m", "aeroexec", *arguments]
        actions[name] = lambda command=command: child_cpu(command, root)
    medians = interleaved(actions, args.repeat)
    print(f"start-up, CPU of a fresh process, median of {args.repeat} interleaved runs")
    failed = False
    for name, (_, target) in CASES.items():
        figure = Figure(
            name, medians[name], medians["python -c pass"], "python -c pass", target, kind="max"
        )
        failed |= not figure.ok
        print(figure.line())
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
