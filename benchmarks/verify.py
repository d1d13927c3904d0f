"""Benchmark: `aeroexec verify` on a large generated catalog vs PyYAML parsing it.

Generates a 10,000-behavior / 1,000-list / 2,000-capability catalog (thesis dialect,
with a sprinkling of real defects so that rules have something to report), then times

* PyYAML alone: `yaml.load(text, Loader=yaml.CSafeLoader)`;
* `aeroexec.verifier.verify_catalog_file(path)`: lenient load with marks + every rule.

Target (design.md section 10): verify <= 3x the PyYAML parse time. Prints both figures,
the ratio and the target; exits 1 when the target is missed.

    .venv/bin/python benchmarks/verify.py [--behaviors 10000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import random
import sys
import tempfile
import time
from pathlib import Path

import yaml

TARGET_RATIO = 3.0


def generate_catalog(
    behaviors: int = 10_000, lists: int = 1_000, capabilities: int = 2_000, seed: int = 7
) -> str:
    """A large catalog shaped like the real ones, scaled up.

    Behaviors come in groups of `behaviors / lists`; each group is one list that all its
    members name (so they preempt each other, as motion behaviors do) and owns
    `capabilities / lists` capabilities, some of them incompatible with each other or
    requiring another. A few behaviors also name a second list, a few capabilities are
    active by default, and about one entry in a hundred carries a real-world defect (a
    misspelled list, an undefined capability, an undefined list member, a conflict
    across groups), so that rules have something to report.
    """
    rng = random.Random(seed)
    per_group = max(1, capabilities // lists)
    group_caps = [[g * per_group + i for i in range(per_group)] for g in range(lists)]
    conflicting = {g for g in range(lists) if g % 5 == 0 and per_group > 1}
    requiring = {g for g in range(lists) if g % 7 == 0 and g not in conflicting and per_group > 1}
    defaults = {c for c in range(capabilities) if c % 400 == 399}
    out: list[str] = ["behavior_descriptors:"]
    members: list[list[str]] = [[] for _ in range(lists)]
    for i in range(behaviors):
        name = f"BEHAVIOR_{i:05d}"
        group = i % lists
        members[group].append(name)
        caps = group_caps[group]
        if group in conflicting:
            chosen = [rng.choice(caps[:2]), *caps[2:]]  # never both incompatible ones
        else:
            chosen = sorted(rng.sample(caps, rng.randint(1, len(caps))))
        recurrent = rng.random() < 0.1
        out.append(f"  - behavior: {name}")
        if not recurrent:
            out.append(f"    timeout: {rng.randint(5, 120)}")
        out.append(f"    recurrent: {'yes' if recurrent else 'no'}")
        named = [f"list_{group:04d}"]
        if rng.random() < 0.02:
            named.append(f"list_{rng.randrange(lists):04d}")
        if rng.random() < 0.003:
            named.append(f"list_{group:04d}_typo")
        out.append(f"    incompatible_lists: [{', '.join(named)}]")
        cap_names = [f"CAPABILITY_{c:04d}" for c in chosen]
        if rng.random() < 0.003:
            cap_names.append("CAPABILITY_UNDEFINED")
        out.append(f"    capabilities: [{', '.join(cap_names)}]")
        if rng.random() < 0.5:
            out.append("    arguments:")
            out.append("      - argument: COORDINATES")
            out.append("        allowed_values: [-100, 100]")
            out.append("        dimensions: 3")
            out.append("      - argument: DIRECTION")
            out.append("        allowed_values: [LEFT, RIGHT, UP, DOWN]")
    out.append("")
    out.append("behavior_lists:")
    for group, names in enumerate(members):
        out.append(f"  - list: list_{group:04d}")
        out.append("    behaviors:")
        out.extend(f"      - {m}" for m in names)
        if rng.random() < 0.01:
            out.append(f"      - UNDEFINED_BEHAVIOR_{group}")
    out.append("")
    out.append("capability_descriptors:")
    for c in range(capabilities):
        group, index = divmod(c, per_group)
        out.append(f"  - capability: CAPABILITY_{c:04d}")
        out.append(f"    active_by_default: {'yes' if c in defaults else 'no'}")
        procs = ", ".join(f"process_{c:04d}_{p}" for p in range(rng.randint(1, 3)))
        out.append(f"    processes: [{procs}]")
        conflicts = []
        if group in conflicting and index < 2:
            conflicts.append(f"CAPABILITY_{group * per_group + 1 - index:04d}")
        if rng.random() < 0.002 and c not in defaults:
            other = rng.randrange(capabilities)
            if other not in defaults and other // per_group != group:
                conflicts.append(f"CAPABILITY_{other:04d}")
        out.append(f"    incompatible_capabilities: [{', '.join(conflicts)}]")
        if group in requiring and index == 1:
            out.append(f"    required_capabilities: [CAPABILITY_{c - 1:04d}]")
    out.append("")
    return "\n".join(out)


def _best(times: list[float]) -> float:
    return min(times)


def run(behaviors: int, lists: int, capabilities: int, repeat: int) -> int:
    from aeroexec.verifier import verify_catalog_file

    text = generate_catalog(behaviors, lists, capabilities)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "big.yaml"
        path.write_text(text, encoding="utf-8")
        parse_times: list[float] = []
        verify_times: list[float] = []
        findings = 0
        for _ in range(repeat):
            start = time.perf_counter()
            yaml.load(path.read_text(encoding="utf-8"), Loader=yaml.CSafeLoader)
            parse_times.append(time.perf_counter() - start)
            start = time.perf_counter()
            report = verify_catalog_file(path)
            verify_times.append(time.perf_counter() - start)
            findings = len(report.findings)
    parse, verify = _best(parse_times), _best(verify_times)
    ratio = verify / parse
    size = len(text.encode()) / 1e6
    print(
        f"catalog: {behaviors} behaviors, {lists} lists, {capabilities} capabilities "
        f"({size:.1f} MB), {findings} findings"
    )
    print(f"PyYAML parse (CSafeLoader): {parse:.3f} s")
    print(f"aeroexec verify:            {verify:.3f} s")
    verdict = "met" if ratio <= TARGET_RATIO else "MISSED"
    print(f"ratio: {ratio:.2f}x (target <= {TARGET_RATIO:g}x: {verdict})")
    return 0 if ratio <= TARGET_RATIO else 1


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--behaviors", type=int, default=10_000)
    parser.add_argument("--lists", type=int, default=1_000)
    parser.add_argument("--capabilities", type=int, default=2_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args(argv)
    return run(args.behaviors, args.lists, args.capabilities, args.repeat)


if __name__ == "__main__":
    sys.exit(main())
