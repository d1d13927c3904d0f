"""Property tests: no input makes the catalog loader (or `catalog show`) fail other than
with a `CatalogError`, and well-formed catalogs are read back exactly as written.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from aeroexec.catalog import Catalog, Severity, check_arguments, parse_catalog
from aeroexec.catalog.loader import (
    ARGUMENT_TAGS,
    BEHAVIOR_TAGS,
    CAPABILITY_TAGS,
    LIST_TAGS,
    TOP_LEVEL_TAGS,
)
from aeroexec.catalog.show import catalog_to_json, render_plain
from aeroexec.cli import app
from aeroexec.errors import CatalogError

FUZZ = settings(
    max_examples=200,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
TAGS = sorted(
    {*TOP_LEVEL_TAGS, *BEHAVIOR_TAGS, *LIST_TAGS, *CAPABILITY_TAGS, *ARGUMENT_TAGS}
    | {"activate_by_default", "behaviors", "tasks", "default_values"}
)
NAMES = st.sampled_from(["A", "B", "C", "moves", "turns", "CAM", "FLY", "a", "TEXT"])

scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(10**30), max_value=10**30),
    # Beyond a float's range: every number the reader converts must survive these.
    st.sampled_from([10**400, -(10**400), 2**1024]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=12),
    st.sampled_from(["yes", "no", "goal_based", "recurrent", "TEXT", "", "15"]),
)
keys = st.one_of(st.sampled_from(TAGS), st.text(max_size=8))
values = st.recursive(
    scalars,
    lambda inner: st.one_of(st.lists(inner, max_size=4), st.dictionaries(keys, inner, max_size=4)),
    max_leaves=20,
)


def maybe(strategy: st.SearchStrategy[Any]) -> st.SearchStrategy[Any]:
    """Usually the right shape, sometimes anything."""
    return st.one_of(strategy, strategy, values)


names_list = maybe(st.lists(NAMES, max_size=4))
argument = st.fixed_dictionaries(
    {"argument": maybe(NAMES)},
    optional={
        "allowed_values": maybe(
            st.one_of(
                st.just("TEXT"),
                st.lists(st.one_of(st.integers(-5, 5), st.floats(), NAMES), max_size=4),
            )
        ),
        "dimensions": maybe(st.integers(-1, 4)),
    },
)
behavior = st.fixed_dictionaries(
    {"behavior": maybe(NAMES)},
    optional={
        "timeout": maybe(st.one_of(st.integers(-1, 100), st.floats())),
        "recurrent": maybe(st.sampled_from(["yes", "no", True, False])),
        "category": maybe(st.sampled_from(["goal_based", "recurrent"])),
        "incompatible_lists": names_list,
        "capabilities": names_list,
        "arguments": maybe(st.lists(argument, max_size=3)),
        "timeot": values,
    },
)
behavior_list = st.fixed_dictionaries({"list": maybe(NAMES)}, optional={"behaviors": names_list})
capability = st.fixed_dictionaries(
    {"capability": maybe(NAMES)},
    optional={
        "processes": names_list,
        "process_sequence": names_list,
        "active_by_default": maybe(st.sampled_from(["yes", "no"])),
        "activate_by_default": maybe(st.booleans()),
        "incompatible_capabilities": names_list,
        "required_capabilities": names_list,
    },
)
catalog_like = st.fixed_dictionaries(
    {},
    optional={
        "behavior_descriptors": maybe(st.lists(behavior, max_size=4)),
        "behavior_lists": maybe(st.lists(behavior_list, max_size=3)),
        "capability_descriptors": maybe(st.lists(capability, max_size=3)),
        "default_behavior_values": maybe(
            st.fixed_dictionaries(
                {},
                optional={
                    "timeout": maybe(st.integers(0, 30)),
                    "category": maybe(st.sampled_from(["goal_based", "recurrent"])),
                },
            )
        ),
        "reactive_activation": values,
        "tasks": values,
    },
)
yamlish = st.text(alphabet=[*"ab:-[]{},&*!|>'\"#%@`?~ \t\n0.1yes", "\x00", "é"], max_size=120)


def dump(document: Any) -> str:
    return yaml.safe_dump(document, allow_unicode=True, sort_keys=False)


def check_catalog(text: str) -> Catalog | None:
    """parse_catalog either returns a catalog that every consumer can use, or raises
    CatalogError with a one-line message and a mark inside the document."""
    # YAML 1.1 also breaks lines at NEL, LS and PS, and marks count lines its way.
    lines = sum(text.count(c) for c in ("\n", "\x85", "\u2028", "\u2029")) + 2
    try:
        catalog = parse_catalog(text, "fuzz.yaml")
    except CatalogError as err:
        assert "\n" not in str(err)
        assert err.mark is not None and err.mark.file == "fuzz.yaml"
        assert 0 <= err.mark.line <= lines
        return None
    for diagnostic in catalog.diagnostics:
        assert 1 <= diagnostic.mark.line <= lines, diagnostic
        assert "\n" not in str(diagnostic)
    # Lenient results reach the verifier and `catalog show`: they must render.
    render_plain(catalog)
    json.dumps(catalog_to_json(catalog), allow_nan=False)
    for descriptor in catalog.behaviors.values():
        for spec in descriptor.arguments:
            check_arguments(descriptor, {spec.name: 1, spec.name.lower(): [1.5, "x"]})
        assert set(catalog.preempted_by(descriptor.name)) <= {
            m for lst in catalog.lists.values() for m in lst.behaviors
        }
    return catalog


@FUZZ
@given(values)
def test_random_documents(document: Any) -> None:
    check_catalog(dump(document))


@FUZZ
@given(catalog_like)
def test_catalog_shaped_documents(document: Any) -> None:
    check_catalog(dump(document))


@FUZZ
@given(st.one_of(yamlish, st.text(max_size=80)))
def test_random_text(text: str) -> None:
    check_catalog(text)


# -- read back what was written -----------------------------------------------------------

NAME = st.text(alphabet="ABCDEFGHIJ_", min_size=1, max_size=6)


@st.composite
def well_formed(draw: st.DrawFn) -> dict[str, Any]:
    behavior_names = draw(st.lists(NAME, min_size=1, max_size=5, unique=True))
    list_names = draw(st.lists(NAME.map(str.lower), max_size=3, unique=True))
    capability_names = draw(st.lists(NAME.map(lambda s: "C" + s), max_size=4, unique=True))
    behaviors = []
    for name in behavior_names:
        recurrent = draw(st.booleans())
        entry: dict[str, Any] = {"behavior": name, "recurrent": "yes" if recurrent else "no"}
        if not recurrent:
            entry["timeout"] = draw(
                st.one_of(st.integers(1, 10**6), st.floats(0.001, 1e6, allow_nan=False))
            )
        entry["incompatible_lists"] = draw(st.lists(st.sampled_from(list_names or ["x"])))
        entry["capabilities"] = draw(st.lists(st.sampled_from(capability_names or ["Cx"])))
        low = draw(st.integers(-100, 100))
        entry["arguments"] = [
            {"argument": "ARG", "allowed_values": [low, low + draw(st.integers(0, 50))]}
        ]
        behaviors.append(entry)
    lists = [
        {"list": name, "behaviors": draw(st.lists(st.sampled_from(behavior_names)))}
        for name in list_names
    ]
    capabilities = [
        {
            "capability": name,
            "active_by_default": draw(st.booleans()),
            "processes": draw(st.lists(NAME, min_size=1, max_size=3)),
            "incompatible_capabilities": draw(st.lists(st.sampled_from(capability_names))),
        }
        for name in capability_names
    ]
    return {
        "behavior_descriptors": behaviors,
        "behavior_lists": lists,
        "capability_descriptors": capabilities,
    }


@FUZZ
@given(well_formed())
def test_well_formed_catalogs_read_back_exactly(document: dict[str, Any]) -> None:
    catalog = check_catalog(dump(document))
    assert catalog is not None
    assert not [d for d in catalog.diagnostics if d.severity is Severity.ERROR]
    assert list(catalog.behaviors) == [b["behavior"] for b in document["behavior_descriptors"]]
    for written in document["behavior_descriptors"]:
        read = catalog.behaviors[written["behavior"]]
        assert read.recurrent == (written["recurrent"] == "yes")
        if read.recurrent:
            assert read.timeout is None
        else:
            assert math.isclose(read.timeout or 0, written["timeout"])
        assert list(read.incompatible_lists) == written["incompatible_lists"]
        assert list(read.capabilities) == written["capabilities"]
        (arg,) = read.arguments
        assert [arg.minimum, arg.maximum] == written["arguments"][0]["allowed_values"]
        victims = {
            m
            for lst in document["behavior_lists"]
            if lst["list"] in written["incompatible_lists"]
            for m in lst["behaviors"]
        }
        assert catalog.preempted_by(written["behavior"]) == victims
    for written in document["capability_descriptors"]:
        read_cap = catalog.capabilities[written["capability"]]
        assert list(read_cap.processes) == written["processes"]
        assert read_cap.active_by_default is written["active_by_default"]
        for other in written["incompatible_capabilities"]:
            assert other in catalog.conflicts_of(written["capability"])
            assert written["capability"] in catalog.conflicts_of(other)


# -- through the CLI ----------------------------------------------------------------------

runner = CliRunner()


@pytest.fixture(scope="module")
def fuzz_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("fuzz") / "catalog.yaml"


def cli_never_tracebacks(path: Path, data: bytes) -> None:
    path.write_bytes(data)
    for extra in ([], ["--format", "json"]):
        result = runner.invoke(app, ["catalog", "show", str(path), *extra])
        assert result.exception is None or isinstance(result.exception, SystemExit), repr(
            result.exception
        )
        assert "Traceback" not in result.output
        assert result.exit_code in (0, 2)
        if result.exit_code == 2:
            assert len(result.stderr.splitlines()) == 1
            assert result.stderr.startswith(f"{path}:")
        elif extra:
            json.loads(result.stdout)


@FUZZ
@given(st.one_of(catalog_like.map(dump), values.map(dump), yamlish).map(str.encode))
def test_cli_never_prints_a_traceback(fuzz_file: Path, data: bytes) -> None:
    cli_never_tracebacks(fuzz_file, data)


@settings(max_examples=50, deadline=None)
@given(st.binary(max_size=200))
def test_cli_random_bytes(fuzz_file: Path, data: bytes) -> None:
    cli_never_tracebacks(fuzz_file, data)
