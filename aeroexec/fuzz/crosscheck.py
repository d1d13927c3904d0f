"""The verifier's findings against the fuzzer's, for one catalog.

Each dynamic violation either corresponds to a verifier finding — one of the rules that
can cause that property's violation (`CAUSES`), about a behavior or capability the
counterexample uses — or is a gap of the verifier. Each verifier error either has a
dynamic witness (a counterexample it corresponds to) or is static-only, with the reason
(`STATIC_ONLY`): most are defects the executive refuses or repairs at run time (a refused
activation is not a violated property), or that no mission can reach.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from aeroexec.catalog.model import Catalog, Severity
from aeroexec.fuzz.search import Finding
from aeroexec.fuzz.steps import Fault, commands, ending_for
from aeroexec.verifier.findings import Finding as StaticFinding

#: Which verifier rules describe a defect that can make each property fail. Not AX602 or
#: AX604 (a timeout shorter than a duration or a travel): their defect ends the behavior
#: in TIME_OUT, which answers its activation and lands nothing in the air (`STATIC_ONLY`).
CAUSES: dict[str, tuple[str, ...]] = {
    "compatible_capabilities": ("AX301", "AX302", "AX303", "AX304", "AX305"),
    "ends_landed_disarmed": ("AX201", "AX301", "AX304", "AX401", "AX402"),
    "activations_answered": ("AX601",),
    "grounded_lands": (),
}
#: Faults after which the simulated vehicle cannot be landed by anything a catalog says:
#: a seized motor holds it where it is; during a lost link every command, the landing
#: included, is refused, so a mission that ends then leaves it flying.
WORLD_FAULTS = ("stuck_motor", "lost_link")

#: Why a verifier finding has no dynamic witness, by rule.
STATIC_ONLY: dict[str, str] = {
    "AX101": "the executive refuses a catalog without an error tag: nothing runs",
    "AX105": "the executive refuses a value of the wrong type: nothing runs",
    "AX108": "the executive refuses a malformed argument: nothing runs",
    "AX201": "an undefined list preempts nothing; the missing preemption shows as a refused "
    "activation or two behaviors side by side, which no safety property forbids",
    "AX202": "a name that is not a behavior cannot be activated (refused as unknown)",
    "AX203": "the behavior's activation is refused (its capability is undefined): "
    "a refusal, not a violation",
    "AX205": "the capability's activation is refused (what it requires is undefined): "
    "a refusal, not a violation",
    "AX301": "the resource manager refuses every activation of the behavior: a refusal, "
    "not a violation",
    "AX302": "initiation refuses conflicting default capabilities before any mission runs",
    "AX303": "the resource manager refuses the behavior while the default holds the "
    "conflicting capability: a refusal, not a violation",
    "AX304": "the resource manager checks capabilities on every activation and refuses "
    "the second behavior: a refusal, not a violation",
    "AX502": "the activation needing the cycle is refused: a refusal, not a violation",
    "AX602": "the wait ends in TIME_OUT before its duration: an answered activation, with "
    "the vehicle where it was (hovering or landed), which no safety property forbids",
    "AX604": "the flight ends in TIME_OUT short of its target: an answered activation, "
    "the vehicle hovering where it got, which no safety property forbids; a landing "
    "that then times out in the air is the landing behavior's timeout, not this one "
    "(it fails as well when this timeout covers the travel)",
}
DEFAULT_REASON = "no generated mission broke a property through it within the budget"


@dataclass(frozen=True)
class DynamicRow:
    finding: Finding
    #: The verifier findings it corresponds to (rule, line), or none: a verifier gap.
    matches: tuple[StaticFinding, ...]
    note: str = ""


@dataclass(frozen=True)
class StaticRow:
    finding: StaticFinding
    #: The counterexample that witnesses it, or None (static-only, with `reason`).
    witness: Finding | None
    reason: str = ""


@dataclass(frozen=True)
class CrossCheck:
    dynamic: tuple[DynamicRow, ...]
    static: tuple[StaticRow, ...]


def touched(finding: Finding, catalog: Catalog) -> set[str]:
    """The behaviors a counterexample commands (its ending included) and their
    capabilities: what a verifier finding that explains it is about (its first subject)."""
    names = {c.behavior for c in commands(finding.mission)}
    names |= {c.behavior for c in ending_for(finding.mission, catalog).commands()}
    for name in list(names):
        descriptor = catalog.behaviors.get(name)
        if descriptor is not None:
            names.update(descriptor.capabilities)
    return names


def _note(finding: Finding) -> str:
    if any(isinstance(s, Fault) and s.kind in WORLD_FAULTS for s in finding.mission):
        return (
            "the simulator's seized motor holds the vehicle where it is: nothing a catalog "
            "declares can land it (the world's, not the catalog's)"
        )
    if finding.name.startswith("invariant:"):
        return "an executive defect: no catalog rule describes it"
    return ""


def cross_check(
    catalog: Catalog, dynamic: Sequence[Finding], static: Sequence[StaticFinding]
) -> CrossCheck:
    rows = []
    witnessed: dict[int, Finding] = {}
    for finding in dynamic:
        near = touched(finding, catalog)
        note = _note(finding)
        causes = () if note else CAUSES.get(finding.name, ())
        matches = tuple(
            s
            for s in static
            if s.rule in causes
            and s.severity is not Severity.INFO
            and s.subjects
            and s.subjects[0] in near
        )
        for s in matches:
            witnessed.setdefault(id(s), finding)
        rows.append(DynamicRow(finding, matches, note))
    errors = []
    for s in static:
        if s.severity is Severity.ERROR or id(s) in witnessed:
            witness = witnessed.get(id(s))
            reason = "" if witness else STATIC_ONLY.get(s.rule, DEFAULT_REASON)
            errors.append(StaticRow(s, witness, reason))
    return CrossCheck(tuple(rows), tuple(errors))


# -- the document ------------------------------------------------------------------------


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def mission_cell(finding: Finding) -> str:
    """A counterexample on one line: its calls, then its faults."""
    parts = []
    for step in finding.mission:
        if isinstance(step, Fault):
            parts.append(f"fault {step.kind} at {step.at_s:g} s")
        else:
            args = ", ".join(f"{n.lower()}={v!r}" for n, v in step.arguments)
            verb = {"execute": "", "activate": "activate ", "inhibit": "inhibit "}[step.action]
            parts.append(f"{verb}{step.behavior}" + (f"({args})" if args else ""))
    return "`" + "; ".join(parts) + "`" if parts else "(the ending alone)"


def markdown(name: str, check: CrossCheck) -> list[str]:
    """The two tables of one catalog."""
    lines = ["", "Dynamic violations (the fuzzer's, shrunk):", ""]
    if check.dynamic:
        lines += ["| property | counterexample | verifier finding |", "| --- | --- | --- |"]
        for row in check.dynamic:
            if row.matches:
                found = ", ".join(f"{m.rule} (line {m.line})" for m in row.matches)
            else:
                found = "**verifier gap**" + (f": {row.note}" if row.note else "")
            lines.append(
                f"| `{row.finding.name}` | {_cell(mission_cell(row.finding))} | {_cell(found)} |"
            )
    else:
        lines.append("None.")
    lines += ["", "Verifier errors (and warnings with a dynamic witness):", ""]
    if check.static:
        lines += ["| rule | line | finding | dynamic witness |", "| --- | --- | --- | --- |"]
        for srow in check.static:
            what = srow.finding.message
            what = what if len(what) <= 90 else what[:87] + "..."
            seen = (
                f"`{srow.witness.name}`: {mission_cell(srow.witness)}"
                if srow.witness is not None
                else f"static-only: {srow.reason}"
            )
            lines.append(
                f"| {srow.finding.rule} | {srow.finding.line} | {_cell(what)} | {_cell(seen)} |"
            )
    else:
        lines.append("None.")
    return lines
