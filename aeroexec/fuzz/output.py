"""What `aeroexec fuzz -o DIR` writes, and the failure database it reads first.

    DIR/findings.json             every finding: property, message, steps, files
    DIR/failures.json             the database: missions that failed, re-run first
    DIR/NN-PROPERTY/mission.py    the shrunk mission (`aeroexec run` runs it)
    DIR/NN-PROPERTY/world.yaml    its world: the default one, with its faults
    DIR/NN-PROPERTY/run.mcap      its recording
    DIR/NN-PROPERTY/violation.txt the violated property, and the commands that show it

Each counterexample is run again from its written files, as `aeroexec run` runs them, and
recorded; its recording is checked as `aeroexec check` checks it: `reproduced` says both
saw the property violated again. Every file is written whole or not at all, and the same
findings give the same bytes.
"""

from __future__ import annotations

import json
import shlex
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from aeroexec.errors import FuzzError, Mark
from aeroexec.fuzz.oracle import Bench, run_files
from aeroexec.fuzz.search import Finding, FuzzReport, mission_from_json, steps_json
from aeroexec.fuzz.steps import Mission, commands
from aeroexec.inputs import read_text
from aeroexec.outputs import whole_file_or_none
from aeroexec.properties.check import VIOLATED, check_recording

FINDINGS = "findings.json"
DATABASE = "failures.json"
MISSION = "mission.py"
WORLD = "world.yaml"
RECORDING = "run.mcap"
VIOLATION = "violation.txt"
FORMAT = 1


def write_text(path: Path, text: str) -> None:
    with whole_file_or_none(path, FuzzError) as temp:
        temp.write_text(text, encoding="utf-8")


def _json(data: Any) -> str:
    return json.dumps(data, indent=2, sort_keys=True, ensure_ascii=False) + "\n"


# -- the database ------------------------------------------------------------------------


def read_database(directory: Path, catalog: str) -> list[Mission]:
    """The missions that failed on `catalog` before (its file name is the key), in the
    database's order; nothing when there is no database yet."""
    path = directory / DATABASE
    if not path.exists():
        return []
    text = read_text(path, "a fuzz failure database", FuzzError)
    try:
        data = json.loads(text)
        entries = data["missions"]
        return [
            mission_from_json(entry["steps"])
            for entry in entries
            if entry["catalog"] == Path(catalog).name
        ]
    except json.JSONDecodeError as exc:
        raise FuzzError(f"not JSON: {exc.msg}", Mark(str(path), exc.lineno, exc.colno)) from None
    except (KeyError, TypeError, ValueError) as exc:
        raise FuzzError(
            f"not a failure database aeroexec fuzz wrote ({type(exc).__name__}: {exc}); "
            "remove it to start afresh",
            Mark(str(path)),
        ) from None


def write_database(directory: Path, catalog: str, findings: Sequence[Finding]) -> None:
    """Keep other catalogs' entries; this catalog's are now its findings (a mission that
    passes again leaves the database, as pytest's --lf forgets a test that passes)."""
    path = directory / DATABASE
    name = Path(catalog).name
    kept: list[dict[str, Any]] = []
    if path.exists():
        kept = [
            e
            for e in json.loads(path.read_text(encoding="utf-8"))["missions"]
            if e["catalog"] != name
        ]
    for finding in findings:
        kept.append(
            {
                "catalog": name,
                "property": finding.name,
                "steps": json.loads(steps_json(finding.mission)),
            }
        )
    kept.sort(key=lambda e: (e["catalog"], e["property"], json.dumps(e["steps"], sort_keys=True)))
    write_text(path, _json({"format": FORMAT, "missions": kept}))


# -- the counterexamples -----------------------------------------------------------------


@dataclass(frozen=True)
class Written:
    finding: Finding
    folder: Path
    reproduced: bool
    #: The properties the written mission's run and its recording's check found violated.
    run_violations: tuple[str, ...]
    check_violations: tuple[str, ...]


def folder_name(index: int, name: str) -> str:
    safe = "".join(c if c.isalnum() or c in "-_." else "-" for c in name)
    return f"{index:02d}-{safe}"


def commands_for(bench: Bench, folder: Path) -> tuple[str, str]:
    """The `aeroexec run` and `aeroexec check` command lines that show the violation."""
    target = bench.target
    specs = " ".join(f"--spec {shlex.quote(s)}" for s in target.specs)
    extra = " --allow-unimplemented" if target.allow_unimplemented else ""
    seed = f" --seed {target.seed}" if target.seed else ""
    for source in target.behaviors.command_line if target.behaviors is not None else ():
        extra += f" -b {shlex.quote(source)}"
    mission, world = shlex.quote(str(folder / MISSION)), shlex.quote(str(folder / WORLD))
    record = shlex.quote(str(folder / RECORDING))
    run = (
        f"aeroexec run {mission} -c {shlex.quote(target.catalog)} -w {world}{seed}"
        f"{extra} {specs} -o {record}"
    )
    return run, f"aeroexec check {record} {specs}"


def write_counterexample(bench: Bench, folder: Path, finding: Finding, fuzz_seed: int) -> Written:
    folder.mkdir(parents=True, exist_ok=True)
    run, check = commands_for(bench, folder)
    header = (
        f"aeroexec fuzz found this mission: it violates {finding.name}",
        f"({finding.message}).",
        f"Catalog {Path(bench.target.catalog).name}, fuzz seed {fuzz_seed}. To see it fail:",
        f"  {run}",
        f"  {check}",
    )
    mission_text, world_text = bench.texts(finding.mission, header)
    write_text(folder / MISSION, mission_text)
    write_text(folder / WORLD, world_text)
    with whole_file_or_none(folder / RECORDING) as temp:
        judgement = run_files(bench, folder / MISSION, folder / WORLD, temp)
    ran = tuple(v.name for v in judgement.violations)
    checked = tuple(
        v.name
        for v in check_recording(folder / RECORDING, bench.properties).verdicts
        if v.status == VIOLATED
    )
    if finding.name.startswith("invariant:"):
        reproduced = finding.name in ran  # the executive's books are not in a recording
    else:
        reproduced = finding.name in ran and finding.name in checked
    lines = [
        f"property: {finding.name}",
        f"violation: {finding.message}",
        f"commands: {len(commands(finding.mission))} generated"
        f" + {len(bench.ending(finding.mission).commands())} of the ending;"
        f" faults: {len(finding.mission) - len(commands(finding.mission))}",
        f"reproduced from these files: {'yes' if reproduced else 'NO'}"
        f" (run: {', '.join(ran) or 'nothing violated'};"
        f" check: {', '.join(checked) or 'nothing violated'})",
        "",
        run,
        check,
    ]
    write_text(folder / VIOLATION, "\n".join(lines) + "\n")
    return Written(finding, folder, reproduced, ran, checked)


#: What a counterexample's folder holds (a folder with anything else is not removed).
FOLDER_FILES = frozenset({MISSION, WORLD, RECORDING, VIOLATION})


def remove_stale(directory: Path, written: Sequence[Written]) -> list[str]:
    """Remove the counterexample folders an earlier run left that this one did not write
    (a property that holds now), so DIR shows this run's findings only; a folder holding
    anything aeroexec fuzz did not write is left alone. Returns what was removed."""
    keep = {w.folder.name for w in written}
    removed = []
    for folder in sorted(directory.iterdir()):
        name = folder.name
        if not (folder.is_dir() and name[:2].isdigit() and name[2:3] == "-") or name in keep:
            continue
        files = list(folder.iterdir())
        if all(f.is_file() and f.name in FOLDER_FILES for f in files):
            for f in files:
                f.unlink()
            folder.rmdir()
            removed.append(name)
    return removed


def write_findings(
    directory: Path,
    bench: Bench,
    report: FuzzReport,
    written: Sequence[Written],
    *,
    seed: int,
    budget: str,
) -> None:
    data = {
        "format": FORMAT,
        "catalog": Path(bench.target.catalog).name,
        "seed": seed,
        "budget": budget,
        "specs": list(bench.target.specs),
        "fault_kinds": list(bench.target.fault_kinds)
        if bench.target.fault_kinds is not None
        else None,
        "findings": [
            {
                "property": w.finding.name,
                "message": w.finding.message,
                "commands": len(commands(w.finding.mission)),
                "steps": json.loads(steps_json(w.finding.mission)),
                "folder": w.folder.name,
                "reproduced": w.reproduced,
            }
            for w in written
        ],
    }
    write_text(directory / FINDINGS, _json(data))
