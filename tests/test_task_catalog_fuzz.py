"""Property tests: no shape of an Aerostack 4.x task catalog makes `aeroexec verify`
print a traceback.

Every field of the task reader is given, now and then, a value of the wrong shape (a
mapping or a list where a scalar belongs, an integer too large for a float, NaN, a
boolean): the reader must report it as a finding at its place, like any other defect,
never fail with a TypeError (`category: {a: 1}` once did: "unhashable type") or an
OverflowError (`allowed_values: [0, 10**400]` once did).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from aeroexec.cli import app

FUZZ = settings(
    max_examples=150,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
NAMES = st.sampled_from(["TAKE_OFF", "LAND", "T", "B", "x", "15"])
#: Integers beyond a float's range (10**400) are valid YAML and valid Python ints.
HUGE = st.sampled_from([10**400, -(10**400), 2**1024, 2**63])
scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(10**6), 10**6),
    HUGE,
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=8),
    st.sampled_from(
        ["TRUE", "FALSE", "yes", "goal_based", "recurrent", "achieve_goal", "keep_running"]
    ),
)
values = st.recursive(
    scalars,
    lambda inner: st.one_of(
        st.lists(inner, max_size=3), st.dictionaries(st.text(max_size=6), inner, max_size=3)
    ),
    max_leaves=10,
)


def maybe(strategy: st.SearchStrategy[Any]) -> st.SearchStrategy[Any]:
    """Usually the right shape, sometimes anything."""
    return st.one_of(strategy, values)


numbers = st.one_of(st.integers(-100, 100), HUGE, st.floats())
parameter = st.fixed_dictionaries(
    {"parameter": maybe(NAMES)},
    optional={
        "allowed_values": maybe(
            st.one_of(
                st.just("number"),
                st.lists(numbers, min_size=2, max_size=2),
                st.lists(NAMES, max_size=3),
            )
        ),
        "allowed_value": values,
        "dimensions": maybe(st.integers(0, 3)),
    },
)
task_attributes = {
    "timeout": maybe(st.one_of(st.integers(-1, 100), HUGE)),
    "category": maybe(st.sampled_from(["goal_based", "recurrent"])),
    "execution_goal": maybe(st.sampled_from(["achieve_goal", "keep_running"])),
    "start_on_request": maybe(st.sampled_from(["TRUE", "FALSE", "yes"])),
    "automatic_activation": maybe(st.sampled_from(["TRUE", "FALSE"])),
    "reactive_start": maybe(st.sampled_from(["TRUE", "FALSE"])),
    "default": maybe(st.sampled_from(["TRUE", "FALSE"])),
}
task = st.fixed_dictionaries(
    {"task": maybe(NAMES)},
    optional={**task_attributes, "parameters": maybe(st.lists(parameter, max_size=2))},
)
behavior = st.fixed_dictionaries(
    {"behavior": maybe(NAMES)},
    optional={
        "task": maybe(NAMES),
        "package": maybe(NAMES),
        "suitability": maybe(st.one_of(st.integers(0, 100), HUGE, st.floats())),
        "efficacy": maybe(st.integers(0, 100)),
        "requires": maybe(
            st.lists(
                st.fixed_dictionaries(
                    {"task": maybe(NAMES)},
                    optional={"minimum_performance": maybe(st.integers(0, 100))},
                ),
                max_size=2,
            )
        ),
    },
)
default_values = st.one_of(
    st.lists(
        st.one_of(
            st.fixed_dictionaries(
                {
                    "tasks": maybe(
                        st.lists(st.fixed_dictionaries({}, optional=task_attributes), max_size=1)
                    )
                }
            ),
            st.fixed_dictionaries(
                {
                    "behaviors": maybe(
                        st.lists(st.fixed_dictionaries({"suitability": values}), max_size=1)
                    )
                }
            ),
        ),
        max_size=2,
    ),
    values,
)
task_catalog = st.fixed_dictionaries(
    # `behaviors` and `tasks` make it a task catalog (aeroexec.catalog.task_loader).
    {
        "behaviors": maybe(st.lists(behavior, max_size=3)),
        "tasks": maybe(st.lists(task, max_size=3)),
    },
    optional={
        "default_values": default_values,
        "exclusivity_constraints": maybe(
            st.lists(
                st.fixed_dictionaries({"mutually_exclusive": maybe(st.lists(NAMES, max_size=3))}),
                max_size=2,
            )
        ),
    },
)

runner = CliRunner()


@pytest.fixture(scope="module")
def fuzz_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("taskfuzz") / "behavior_catalog.yaml"


def dump(document: Any) -> str:
    return yaml.safe_dump(document, allow_unicode=True, sort_keys=False)


def verify_never_tracebacks(path: Path, document: Any) -> None:
    path.write_text(dump(document), encoding="utf-8")
    for extra in ([], ["--format", "json", "--witness"]):
        result = runner.invoke(app, ["verify", str(path), *extra])
        assert result.exception is None or isinstance(result.exception, SystemExit), repr(
            result.exception
        )
        assert "Traceback" not in result.output
        # A defect of the catalog is a finding (exit 1), not an unreadable input.
        assert result.exit_code in (0, 1), result.output
        if extra:
            report = json.loads(result.stdout)
            for finding in report["findings"]:
                assert finding["file"] == str(path)
                assert finding["line"] >= 1


WRONG_SHAPES: list[Any] = [
    {"behaviors": [{"behavior": "B", "task": "T"}], "tasks": [{"task": "T", "category": {"a": 1}}]},
    {"behaviors": [{"behavior": "B", "task": "T"}], "tasks": [{"task": "T", "category": [1]}]},
    {
        "behaviors": [{"behavior": "B", "task": "T"}],
        "tasks": [{"task": "T", "execution_goal": {"a": 1}}],
    },
    {
        "behaviors": [{"behavior": "B", "task": "T"}],
        "tasks": [
            {"task": "T", "parameters": [{"parameter": "p", "allowed_values": [0, 10**400]}]}
        ],
    },
]


@FUZZ
@given(task_catalog)
@example(WRONG_SHAPES[0])
@example(WRONG_SHAPES[1])
@example(WRONG_SHAPES[2])
@example(WRONG_SHAPES[3])
def test_verify_never_prints_a_traceback(fuzz_file: Path, document: Any) -> None:
    verify_never_tracebacks(fuzz_file, document)


@pytest.mark.parametrize(
    ("document", "key", "message"),
    [
        (WRONG_SHAPES[0], "category:", "category must be goal_based or recurrent, got mapping"),
        (WRONG_SHAPES[1], "category:", "category must be goal_based or recurrent, got list"),
        (
            WRONG_SHAPES[2],
            "execution_goal:",
            "execution_goal must be achieve_goal or keep_running, got mapping",
        ),
        (
            WRONG_SHAPES[3],
            "allowed_values:",
            "T: parameter p: a range bound is NaN or too large for a float",
        ),
    ],
)
def test_a_value_of_the_wrong_shape_is_a_finding_at_its_place(
    tmp_path: Path, document: Any, key: str, message: str
) -> None:
    path = tmp_path / "behavior_catalog.yaml"
    text = dump(document)
    path.write_text(text, encoding="utf-8")
    # The finding is at the value, on the key's line or the next (block style).
    line = next(n for n, row in enumerate(text.splitlines(), 1) if key in row)
    result = runner.invoke(app, ["verify", str(path)])
    assert result.exit_code == 1, result.output
    errors = [x for x in result.stdout.splitlines() if ": error AX8" in x]
    assert len(errors) == 1, result.stdout
    assert errors[0].startswith((f"{path}:{line}:", f"{path}:{line + 1}:")), errors[0]
    assert message in errors[0]
    assert result.stderr == ""
