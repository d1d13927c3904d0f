"""Display a loaded catalog: the thesis' "Prettify" view.

Three renderings of the same facts, all computed by `catalog_facts`:

* `render_plain` — line-oriented text for pipes and tests: stable order, no color,
  no width-dependent wrapping, every diagnostic on its own `file:line:col: ...` line;
* `render_rich` — the same facts for a terminal: headings and wrapped fields that fit
  80 columns without splitting a name;
* `catalog_to_json` — one JSON-able object for machines.

Everything is in catalog order (the executive's tie-break order), so the output of the
same catalog never changes between runs.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from rich.console import Console
from rich.text import Text

from aeroexec.catalog.model import (
    ArgumentSpec,
    BehaviorDescriptor,
    CapabilityDescriptor,
    Catalog,
    Diagnostic,
    Severity,
)
from aeroexec.errors import Mark, one_line

#: Bumped when a JSON field changes meaning or disappears (adding fields is compatible).
JSON_FORMAT = "aeroexec.catalog.show/1"

_DIALECTS = {
    "thesis-2017": "thesis 2017 Appendix A (recurrent, processes, active_by_default)",
    "aerostack-2.x": "Aerostack 2.x (default_behavior_values, category, process_sequence)",
    "mixed": "a mix of the thesis 2017 and Aerostack 2.x dialects",
}
_SEVERITY_STYLE = {Severity.ERROR: "bold red", Severity.WARNING: "yellow", Severity.INFO: "cyan"}


@dataclass(frozen=True, slots=True)
class BehaviorFacts:
    descriptor: BehaviorDescriptor
    preempts: tuple[str, ...]


@dataclass(frozen=True, slots=True)
class CapabilityFacts:
    descriptor: CapabilityDescriptor
    conflicts: tuple[str, ...]
    used_by: tuple[str, ...]


@dataclass(frozen=True, slots=True)
class ListFacts:
    name: str
    behaviors: tuple[str, ...]
    named_by: tuple[str, ...]
    mark: Mark


@dataclass(frozen=True, slots=True)
class CatalogFacts:
    """What every rendering shows, derived once from the catalog's indexes."""

    catalog: Catalog
    behaviors: tuple[BehaviorFacts, ...]
    lists: tuple[ListFacts, ...]
    capabilities: tuple[CapabilityFacts, ...]
    diagnostics: tuple[Diagnostic, ...]


def _unique(names: Iterable[str]) -> tuple[str, ...]:
    return tuple(dict.fromkeys(names))


def preempts(catalog: Catalog, behavior: str) -> tuple[str, ...]:
    """`Catalog.preempted_by` in a stable order: list order, then member order."""
    descriptor = catalog.behaviors[behavior]
    ordered = _unique(
        member
        for list_name in descriptor.incompatible_lists
        if list_name in catalog.lists
        for member in catalog.lists[list_name].behaviors
    )
    victims = catalog.preempted_by(behavior)
    # The index is the executive's truth; keep anything it knows that the lists did not give.
    return ordered + tuple(sorted(victims.difference(ordered)))


def conflicts(catalog: Catalog, capability: str) -> tuple[str, ...]:
    """`Catalog.conflicts_of` in a stable order: catalog order, then undefined ones by name."""
    found = catalog.conflicts_of(capability)
    defined = tuple(name for name in catalog.capabilities if name in found)
    return defined + tuple(sorted(found.difference(defined)))


def catalog_facts(catalog: Catalog) -> CatalogFacts:
    behaviors = tuple(
        BehaviorFacts(descriptor, preempts(catalog, name))
        for name, descriptor in catalog.behaviors.items()
    )
    lists = tuple(
        ListFacts(
            name,
            lst.behaviors,
            tuple(b for b, d in catalog.behaviors.items() if name in d.incompatible_lists),
            lst.mark,
        )
        for name, lst in catalog.lists.items()
    )
    capabilities = tuple(
        CapabilityFacts(
            descriptor,
            conflicts(catalog, name),
            tuple(b for b, d in catalog.behaviors.items() if name in d.capabilities),
        )
        for name, descriptor in catalog.capabilities.items()
    )
    # File order reads best next to the catalog; the sort is stable for equal places.
    diagnostics = tuple(
        sorted(catalog.diagnostics, key=lambda d: (d.mark.file, d.mark.line, d.mark.column))
    )
    return CatalogFacts(catalog, behaviors, lists, capabilities, diagnostics)


# -- small formatters ---------------------------------------------------------------------
def _number(value: float | None) -> str:
    if value is None:
        return "?"
    if math.isfinite(value) and float(value).is_integer():
        return str(int(value))
    return repr(float(value))


def _seconds(timeout: float | None) -> str:
    return "none" if timeout is None else f"{_number(timeout)} s"


def _yes_no(flag: bool) -> str:
    return "yes" if flag else "no"


def _names(names: Iterable[str]) -> str:
    return ", ".join(names) or "-"


def _counts(facts: CatalogFacts) -> str:
    c = facts.catalog
    return (
        f"{len(c.behaviors)} behaviors, {len(c.lists)} lists, {len(c.capabilities)} "
        f"capabilities ({len(c.default_capabilities)} active by default)"
    )


def _severity_counts(diagnostics: Iterable[Diagnostic]) -> str:
    counts = {severity: 0 for severity in Severity}
    for diagnostic in diagnostics:
        counts[diagnostic.severity] += 1
    return ", ".join(f"{n} {s.value}{'s' if n != 1 else ''}" for s, n in counts.items())


def _argument_line(spec: ArgumentSpec) -> str:
    return f"{spec.name}: {spec.describe()}"


# -- plain text ---------------------------------------------------------------------------
def render_plain(catalog: Catalog) -> str:
    """The catalog as stable, uncolored, line-oriented text (ends with a newline).

    Each behavior, list and capability gets a header line indented by two that names
    it (`  TAKE_OFF  timeout 15 s  recurrent no  line 7`, so `grep '^  TAKE_OFF '` finds
    it), then its fields indented by four as `field  value`. Diagnostics come last, one
    compiler-style line each.
    """
    facts = catalog_facts(catalog)
    out: list[str] = [
        f"catalog {catalog.source}",
        f"dialect {catalog.dialect}: {_DIALECTS.get(catalog.dialect, catalog.dialect)}",
        f"summary {_counts(facts)}",
        "",
        f"behaviors ({len(facts.behaviors)})",
    ]

    def field(name: str, value: str) -> None:
        out.append(f"    {name:<26} {value}")

    for b in facts.behaviors:
        d = b.descriptor
        out.append(
            f"  {d.name}  timeout {_seconds(d.timeout)}  recurrent {_yes_no(d.recurrent)}"
            f"  line {d.mark.line}"
        )
        field("incompatible_lists", _names(d.incompatible_lists))
        field("preempts", _names(b.preempts))
        field("capabilities", _names(d.capabilities))
        if not d.arguments:
            field("arguments", "-")
        for spec in d.arguments:
            field("argument", _argument_line(spec))
    out += ["", f"lists ({len(facts.lists)})"]
    for lst in facts.lists:
        out.append(f"  {lst.name}  line {lst.mark.line}")
        field("behaviors", _names(lst.behaviors))
        field("named by", _names(lst.named_by))
    out += ["", f"capabilities ({len(facts.capabilities)})"]
    for c in facts.capabilities:
        d = c.descriptor
        out.append(
            f"  {d.name}  active_by_default {_yes_no(d.active_by_default)}  line {d.mark.line}"
        )
        field("processes", _names(d.processes))
        field("incompatible_capabilities", _names(d.incompatible_capabilities))
        field("conflicts", _names(c.conflicts))
        field("required_capabilities", _names(d.required_capabilities))
        field("used by", _names(c.used_by))
    out += [
        "",
        f"default capabilities: {_names(catalog.default_capabilities)}",
        "",
        VERIFY_NOTE.format(file=catalog.source),
        f"loader diagnostics ({_severity_counts(facts.diagnostics)})",
    ]
    out += [str(d) for d in facts.diagnostics]
    # Names come from the YAML and may hold newlines; one entry must stay one line.
    return "\n".join(one_line(line) for line in out) + "\n"


# -- rich (terminal) ----------------------------------------------------------------------
#: What the loader's diagnostics are not: the verifier's rules (shown with every rendering).
VERIFY_NOTE = "`aeroexec verify {file}` is the check: references, conflicts, start order, missions"


def _wrapped(
    console: Console, indent: int, label: str, label_width: int, value: str, style: str = ""
) -> None:
    """`label  value`, the value wrapped at spaces under itself (a name is never split)."""
    hang = indent + label_width + 2
    width = max(console.width - hang, 20)
    lines = textwrap.wrap(value, width, break_long_words=False, break_on_hyphens=False) or [""]
    for i, line in enumerate(lines):
        text = Text(" " * indent)
        text.append(f"{label if i == 0 else '':<{label_width}}  ", style="dim")
        text.append(line, style=style)
        console.print(text, no_wrap=True, overflow="ignore", crop=False)


def _paragraph(console: Console, parts: list[tuple[str, str]], hang: int = 4) -> None:
    """Styled `parts` as lines of the console's width, broken at spaces only; lines after
    the first indented by `hang`."""
    plain = "".join(text for text, _ in parts)
    lines = textwrap.wrap(
        plain,
        max(console.width, 40),
        subsequent_indent=" " * hang,
        break_long_words=False,
        break_on_hyphens=False,
    )
    styles = [style for text, style in parts for _ in text]
    position = 0
    for number, line in enumerate(lines):
        body = line[hang:] if number else line
        position = plain.index(body, position)
        text = Text(line[: len(line) - len(body)])
        start = 0
        for end in range(1, len(body) + 1):
            if end == len(body) or styles[position + end] != styles[position + start]:
                text.append(body[start:end], style=styles[position + start])
                start = end
        position += len(body)
        console.print(text, no_wrap=True, overflow="ignore", crop=False)


def _heading(console: Console, name: str, style: str, note: str = "", note_style: str = "") -> None:
    text = Text("  ")
    text.append(name, style=style)
    if note:
        text.append(f"  {note}", style=note_style)
    console.print(text, no_wrap=True, overflow="ignore", crop=False)


def _fields(console: Console, fields: list[tuple[str, str]]) -> None:
    shown = [(label, value) for label, value in fields if value]
    width = max((len(label) for label, _ in shown), default=0)
    for label, value in shown:
        _wrapped(console, 6, label, width, value)


def render_rich(catalog: Catalog, console: Console) -> None:
    """The catalog for a terminal of any width (80 columns and up): one heading per
    behavior, list and capability, its non-empty fields under it, wrapped between names
    (never inside one); errors and warnings of the loader, with the count of its infos."""
    facts = catalog_facts(catalog)
    console.print(Text(catalog.source, style="bold"))
    console.print(Text(f"dialect: {_DIALECTS.get(catalog.dialect, catalog.dialect)}", style="dim"))
    console.print(Text(_counts(facts), style="dim"))

    console.print(Text(f"\nBehaviors ({len(facts.behaviors)})", style="bold underline"))
    for b in facts.behaviors:
        d = b.descriptor
        timeout = "no timeout" if d.timeout is None else f"timeout {_seconds(d.timeout)}"
        _heading(console, d.name, "bold", f"{timeout}{', recurrent' if d.recurrent else ''}")
        lists = ", ".join(d.incompatible_lists)
        if lists:
            lists += f" (preempts {len(b.preempts)})"
        _fields(
            console,
            [
                ("incompatible", lists),
                ("capabilities", ", ".join(d.capabilities)),
                *((spec.name, spec.describe()) for spec in d.arguments),
            ],
        )

    console.print(Text(f"\nLists ({len(facts.lists)})", style="bold underline"))
    for lst in facts.lists:
        _heading(console, lst.name, "bold")
        _fields(
            console,
            [("behaviors", ", ".join(lst.behaviors) or "-"), ("named by", ", ".join(lst.named_by))],
        )

    console.print(Text(f"\nCapabilities ({len(facts.capabilities)})", style="bold underline"))
    for c in facts.capabilities:
        d = c.descriptor
        default = "active by default" if d.active_by_default else ""
        _heading(console, d.name, "bold", default, "green")
        _fields(
            console,
            [
                ("processes", ", ".join(d.processes)),
                ("conflicts", ", ".join(c.conflicts)),
                ("requires", ", ".join(d.required_capabilities)),
                ("used by", ", ".join(c.used_by)),
            ],
        )

    console.print(
        Text(f"\nLoader diagnostics ({_severity_counts(facts.diagnostics)})", style="bold")
    )
    infos = 0
    for diagnostic in facts.diagnostics:
        if diagnostic.severity is Severity.INFO:
            infos += 1
            continue
        severity = diagnostic.severity
        _paragraph(
            console,
            [
                (one_line(f"{diagnostic.mark}: "), ""),
                (severity.value, _SEVERITY_STYLE[severity]),
                (one_line(f" {diagnostic.code} {diagnostic.message}"), ""),
            ],
        )
    if infos:
        _paragraph(
            console,
            [(f"{infos} infos not listed here (--color never or -f json lists them)", "dim")],
        )
    _paragraph(console, [(VERIFY_NOTE.format(file=catalog.source), "dim")], hang=0)


# -- JSON ---------------------------------------------------------------------------------
def _json_number(value: float | None) -> float | int | None:
    """Numbers as JSON can hold them: whole floats as ints, +-inf (unbounded) as null."""
    if value is None or not math.isfinite(value):
        return None
    return int(value) if float(value).is_integer() else float(value)


def _place(mark: Mark) -> dict[str, Any]:
    return {"line": mark.line, "column": mark.column}


def _argument_json(spec: ArgumentSpec) -> dict[str, Any]:
    return {
        "name": spec.name,
        "kind": spec.kind.value,
        "minimum": _json_number(spec.minimum),
        "maximum": _json_number(spec.maximum),
        "dimensions": spec.dimensions,
        "symbols": list(spec.symbols),
        "allowed": spec.describe(),
        **_place(spec.mark),
    }


def diagnostic_json(diagnostic: Diagnostic) -> dict[str, Any]:
    return {
        "file": diagnostic.mark.file,
        "line": diagnostic.mark.line,
        "column": diagnostic.mark.column,
        "severity": diagnostic.severity.value,
        "code": diagnostic.code,
        "message": diagnostic.message,
        "subjects": list(diagnostic.subjects),
    }


def catalog_to_json(catalog: Catalog) -> dict[str, Any]:
    """One JSON-able object with everything `render_plain` shows (no NaN/inf inside)."""
    facts = catalog_facts(catalog)
    return {
        "format": JSON_FORMAT,
        "file": catalog.source,
        "dialect": catalog.dialect,
        "counts": {
            "behaviors": len(catalog.behaviors),
            "lists": len(catalog.lists),
            "capabilities": len(catalog.capabilities),
        },
        "default_capabilities": list(catalog.default_capabilities),
        "behaviors": [
            {
                "name": b.descriptor.name,
                **_place(b.descriptor.mark),
                "timeout": _json_number(b.descriptor.timeout),
                "recurrent": b.descriptor.recurrent,
                "incompatible_lists": list(b.descriptor.incompatible_lists),
                "preempts": list(b.preempts),
                "capabilities": list(b.descriptor.capabilities),
                "arguments": [_argument_json(spec) for spec in b.descriptor.arguments],
            }
            for b in facts.behaviors
        ],
        "lists": [
            {
                "name": lst.name,
                **_place(lst.mark),
                "behaviors": list(lst.behaviors),
                "named_by": list(lst.named_by),
            }
            for lst in facts.lists
        ],
        "capabilities": [
            {
                "name": c.descriptor.name,
                **_place(c.descriptor.mark),
                "active_by_default": c.descriptor.active_by_default,
                "processes": list(c.descriptor.processes),
                "incompatible_capabilities": list(c.descriptor.incompatible_capabilities),
                "conflicts": list(c.conflicts),
                "required_capabilities": list(c.descriptor.required_capabilities),
                "used_by": list(c.used_by),
            }
            for c in facts.capabilities
        ],
        "diagnostics": [diagnostic_json(d) for d in facts.diagnostics],
    }
