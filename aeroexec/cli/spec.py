"""`--spec FILE`: properties for `check`, `run`, `fly` and `replay --check`.

The properties package (and numpy, its arrays) is imported only when a command is
given --spec (or is `check`): `aeroexec run` without it starts as fast as before.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Any

import typer

if TYPE_CHECKING:
    from aeroexec.properties.check import Verdict
    from aeroexec.properties.monitor import PropertyMonitor
    from aeroexec.properties.spec import PropertySet

SpecOption = Annotated[
    list[str] | None,
    typer.Option(
        "--spec",
        metavar="FILE",
        help="A property file, or aeroexec:safety (repeatable); docs/properties.md.",
        show_default=False,
    ),
]


def monitor_for(spec: list[str] | None, *, live: bool = False) -> PropertyMonitor | None:
    """A monitor of the properties of `spec` (None without --spec); `PropertyError`
    (one line, exit 2) for a bad property file, before anything runs. `live`: a real
    flight, where properties with an action are judged every tick (real time leaves the
    room; a simulation judges them every 0.5 s of its time)."""
    if not spec:
        return None
    from aeroexec.properties.monitor import CHECK_EVERY_S, PropertyMonitor
    from aeroexec.properties.signals import PERIOD_S
    from aeroexec.properties.spec import load_properties

    every = PERIOD_S if live else CHECK_EVERY_S
    return PropertyMonitor(load_properties(spec), check_every_s=every)


def print_verdicts(verdicts: list[Verdict], source: str) -> bool:
    """One line per violated (or unchecked) property, then a summary; True when a
    property of severity error was violated."""
    from aeroexec.properties.check import CheckReport
    from aeroexec.properties.report import text

    report = CheckReport(source, tuple(verdicts), 0.0)
    typer.echo(text([report]).replace("1 recording(s), ", "properties: "), nl=False)
    return report.failed


#: The properties every what-if run is checked against, besides the user's.
SAFETY = "aeroexec:safety"


def with_safety(spec: list[str] | None) -> list[str]:
    """`spec` with `aeroexec:safety` (first, unless it is already there)."""
    given = list(spec or ())
    return given if SAFETY in given else [SAFETY, *given]


def load_spec(spec: list[str] | None) -> PropertySet | None:
    """The properties of --spec (None without it); `PropertyError` for a bad file."""
    if not spec:
        return None
    from aeroexec.properties.spec import load_properties

    return load_properties(spec)


def verdicts_text(entries: list[dict[str, Any]]) -> str:
    """The verdicts of replays (`ReplayResult.properties`) as `check` prints them."""
    from aeroexec.properties.report import text_of

    return text_of(entries)


def verdicts_failed(entries: list[dict[str, Any]]) -> bool:
    from aeroexec.properties.report import failed

    return failed(entries)


def with_verdicts_json(document: str, entries: list[dict[str, Any]]) -> str:
    """A JSON report with the properties' verdicts added under `properties`."""
    import json

    from aeroexec.properties.report import json_of

    body = json.loads(document)
    body["properties"] = json_of(entries)
    return json.dumps(body, indent=2)


def with_verdicts_junit(document: str, entries: list[dict[str, Any]]) -> str:
    """A JUnit report with one more test suite per checked recording."""
    from xml.etree import ElementTree as ET

    from aeroexec.properties.report import junit_of

    root = ET.fromstring(document)
    if root.tag == "testsuite":  # one suite: both go under <testsuites>
        outer = ET.Element("testsuites", name=root.get("name", ""))
        outer.append(root)
        root = outer
    for suite in ET.fromstring(junit_of(entries)).iter("testsuite"):
        suite.set("name", f"properties: {suite.get('name')}")
        root.append(suite)
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, "unicode")
