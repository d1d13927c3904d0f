"""Property tests: the verifier never crashes on generated catalogs, and its verdicts do
not depend on the order of entries in the file."""

from __future__ import annotations

import json
import random
from collections import Counter
from typing import Any

import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from aeroexec.catalog.loader import parse_catalog
from aeroexec.errors import CatalogError
from aeroexec.verifier import Report, check_catalog
from aeroexec.verifier.report import FORMATS, render

NAMES = st.sampled_from(["A", "B", "C", "D", "E", "TAKE_OFF", "B_", "a"])
LIST_NAMES = st.sampled_from(["l1", "l2", "l3", "l_1", "A"])
CAP_NAMES = st.sampled_from(["C1", "C2", "C3", "C4", "C_1", "A"])
SCALARS = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-5, 2000),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=6),
)


def maybe(value: st.SearchStrategy[Any]) -> st.SearchStrategy[Any]:
    """The value, or something of the wrong shape, or nothing."""
    return st.one_of(value, value, value, SCALARS, st.lists(SCALARS, max_size=2))


ARGUMENT = st.fixed_dictionaries(
    {"argument": maybe(st.sampled_from(["X", "x", "DURATION", "SPEED"]))},
    optional={
        "allowed_values": maybe(
            st.one_of(
                st.just("TEXT"),
                st.lists(st.integers(-10, 2000), min_size=0, max_size=3),
                st.lists(st.sampled_from(["UP", "DOWN", "UP", "7"]), max_size=3),
            )
        ),
        "dimensions": maybe(st.integers(0, 4)),
    },
)
BEHAVIOR = st.fixed_dictionaries(
    {"behavior": maybe(NAMES)},
    optional={
        "timeout": maybe(st.integers(-1, 100)),
        "recurrent": maybe(st.sampled_from(["yes", "no", True])),
        "category": maybe(st.sampled_from(["goal_based", "recurrent", "other"])),
        "incompatible_lists": maybe(st.lists(LIST_NAMES, max_size=3)),
        "capabilities": maybe(st.lists(CAP_NAMES, max_size=3)),
        "arguments": maybe(st.lists(ARGUMENT, max_size=2)),
        "incompatible_list": st.just(["l1"]),
    },
)
LIST = st.fixed_dictionaries(
    {"list": maybe(LIST_NAMES)},
    optional={"behaviors": maybe(st.lists(st.one_of(NAMES, CAP_NAMES), max_size=4))},
)
CAPABILITY = st.fixed_dictionaries(
    {"capability": maybe(CAP_NAMES)},
    optional={
        "processes": maybe(st.lists(st.sampled_from(["p", "q", "r"]), max_size=3)),
        "process_sequence": st.lists(st.sampled_from(["p", "q"]), max_size=2),
        "active_by_default": maybe(st.sampled_from(["yes", "no"])),
        "incompatible_capabilities": maybe(st.lists(CAP_NAMES, max_size=2)),
        "required_capabilities": maybe(st.lists(CAP_NAMES, max_size=2)),
    },
)
CATALOG = st.fixed_dictionaries(
    {},
    optional={
        "behavior_descriptors": maybe(st.lists(BEHAVIOR, max_size=6)),
        "behavior_lists": maybe(st.lists(LIST, max_size=4)),
        "capability_descriptors": maybe(st.lists(CAPABILITY, max_size=5)),
        "default_behavior_values": maybe(
            st.fixed_dictionaries({}, optional={"timeout": SCALARS, "category": SCALARS})
        ),
    },
)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(CATALOG)
def test_generated_catalogs_never_crash_the_verifier(document: dict[str, Any]) -> None:
    text = yaml.safe_dump(document, sort_keys=False)
    try:
        catalog = parse_catalog(text, "generated.yaml")
    except CatalogError:
        return  # unreadable input is a clean, reported refusal
    report = Report(tuple(check_catalog(catalog)), catalogs=("generated.yaml",))
    for finding in report.findings:
        assert finding.file == "generated.yaml"
        assert finding.line >= 0 and finding.column >= 0
        assert finding.message
    for fmt in FORMATS:
        rendered = render(report, fmt, witness=True)
        if fmt in ("json", "sarif"):
            json.loads(rendered)


# -- order independence ---------------------------------------------------------------------
BEHAVIORS = [f"B{i}" for i in range(6)]
LISTS = ["l0", "l1", "l2"]
CAPS = [f"C{i}" for i in range(6)]


@st.composite
def well_formed(draw: st.DrawFn) -> dict[str, Any]:
    """Catalogs with unique names (duplicates make order matter by definition: the last
    definition wins) but every kind of dangling reference and conflict."""
    behaviors = []
    for name in draw(st.lists(st.sampled_from(BEHAVIORS), min_size=1, unique=True)):
        entry: dict[str, Any] = {
            "behavior": name,
            "recurrent": draw(st.sampled_from(["yes", "no"])),
            "incompatible_lists": draw(st.lists(st.sampled_from([*LISTS, "lx"]), max_size=2)),
            "capabilities": draw(st.lists(st.sampled_from([*CAPS, "CX"]), max_size=3)),
        }
        if draw(st.booleans()):
            entry["timeout"] = draw(st.integers(1, 30))
        if draw(st.booleans()):
            entry["arguments"] = [{"argument": "DURATION", "allowed_values": [1, 60]}]
        behaviors.append(entry)
    lists = [
        {"list": name, "behaviors": draw(st.lists(st.sampled_from([*BEHAVIORS, "C0"]), max_size=4))}
        for name in draw(st.lists(st.sampled_from(LISTS), unique=True))
    ]
    capabilities = []
    for name in draw(st.lists(st.sampled_from(CAPS), unique=True)):
        capabilities.append(
            {
                "capability": name,
                "active_by_default": draw(st.sampled_from(["no", "no", "no", "yes"])),
                "processes": draw(st.lists(st.sampled_from(["p", "q", "r", "s"]), max_size=3)),
                "incompatible_capabilities": draw(st.lists(st.sampled_from(CAPS), max_size=2)),
                "required_capabilities": draw(st.lists(st.sampled_from([*CAPS, "CY"]), max_size=2)),
            }
        )
    return {
        "behavior_descriptors": behaviors,
        "behavior_lists": lists,
        "capability_descriptors": capabilities,
    }


def verdicts(document: dict[str, Any]) -> Counter[tuple[str, frozenset[str]]]:
    catalog = parse_catalog(yaml.safe_dump(document, sort_keys=False), "c.yaml")
    return Counter((f.rule, frozenset(f.subjects)) for f in check_catalog(catalog))


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(well_formed(), st.randoms(use_true_random=False))
def test_verdicts_do_not_depend_on_entry_order(
    document: dict[str, Any], rng: random.Random
) -> None:
    shuffled = {key: list(value) for key, value in document.items()}
    for entries in shuffled.values():
        rng.shuffle(entries)
    shuffled = dict(reversed(list(shuffled.items())))  # sections in another order too
    assert verdicts(document) == verdicts(shuffled)
