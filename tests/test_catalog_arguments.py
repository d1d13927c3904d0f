"""Argument validation (`check_arguments`) at its boundaries.

The messages are what a mission author reads (the specialist's `check_behavior_format`
and the verifier's mission checks both use them), so most tests pin the exact text.
"""

from __future__ import annotations

import math
from typing import Any

import pytest

from aeroexec.catalog import (
    ArgumentKind,
    ArgumentSpec,
    BehaviorDescriptor,
    Catalog,
    check_arguments,
)
from aeroexec.catalog.arguments import check_value


@pytest.fixture(scope="module")
def behaviors(thesis_catalog: Catalog) -> dict[str, BehaviorDescriptor]:
    return dict(thesis_catalog.behaviors)


def errors(descriptor: BehaviorDescriptor, **arguments: Any) -> tuple[str, ...]:
    return check_arguments(descriptor, arguments).errors


# -- numeric ranges -----------------------------------------------------------------------


@pytest.mark.parametrize("angle", [-360, 360, -360.0, 360.0, 0, -0.0, 359.999, -90])
def test_range_bounds_are_inclusive(behaviors: dict[str, BehaviorDescriptor], angle: float) -> None:
    check = check_arguments(behaviors["ROTATE"], {"ANGLE": angle})
    assert check.ok and check.errors == ()
    assert check.values == {"ANGLE": angle}
    assert type(check.values["ANGLE"]) is type(angle)  # ints stay ints, floats floats


@pytest.mark.parametrize(
    ("angle", "shown"),
    [
        (361, "361 (361 is outside)"),
        (-361, "-361 (-361 is outside)"),
        (360.0001, "360.0001 (360.0001 is outside)"),
        (-360.5, "-360.5 (-360.5 is outside)"),
        (10**400, None),  # larger than any float: still compared exactly, still outside
        (math.inf, "inf (inf is outside)"),
        (math.nan, "nan (nan is outside)"),  # NaN compares false: must not slip through
    ],
)
def test_range_just_outside(
    behaviors: dict[str, BehaviorDescriptor], angle: float, shown: str | None
) -> None:
    (error,) = errors(behaviors["ROTATE"], ANGLE=angle)
    assert error.startswith("ROTATE: ANGLE needs a number in [-360, 360], got ")
    if shown is not None:
        assert error == f"ROTATE: ANGLE needs a number in [-360, 360], got {shown}"


def test_float_bounds() -> None:
    # JacekCieslak95's flown catalog: `allowed_values: [0.7,5]` (the 2019 checker truncated it).
    spec = ArgumentSpec("ALTITUDE", ArgumentKind.RANGE, 0.7, 5.0)
    take_off = BehaviorDescriptor("TAKE_OFF2", 30.0, False, arguments=(spec,))
    assert check_arguments(take_off, {"altitude": 0.7}).ok
    assert check_arguments(take_off, {"altitude": 5}).ok
    assert errors(take_off, altitude=0.69) == (
        "TAKE_OFF2: ALTITUDE needs a number in [0.7, 5], got 0.69 (0.69 is outside)",
    )


@pytest.mark.parametrize("value", [True, False, [True], "5", None, {"x": 1}])
def test_non_numbers_are_rejected_for_a_scalar_range(
    behaviors: dict[str, BehaviorDescriptor], value: Any
) -> None:
    # bool is an int in Python; `angle=True` is a mission bug, not 1 degree.
    (error,) = errors(behaviors["ROTATE"], angle=value)
    assert error.startswith("ROTATE: ANGLE needs a number in [-360, 360], got ")


def test_bool_message_is_exact(behaviors: dict[str, BehaviorDescriptor]) -> None:
    assert errors(behaviors["ROTATE"], angle=True) == (
        "ROTATE: ANGLE needs a number in [-360, 360], got True",
    )


def test_scalar_range_accepts_a_one_element_list(behaviors: dict[str, BehaviorDescriptor]) -> None:
    check = check_arguments(behaviors["KEEP_HOVERING"], {"duration": [5]})
    assert check.ok
    assert check.values == {"DURATION": 5}  # normalized to the scalar


# -- vectors (dimensions) -----------------------------------------------------------------


def test_wrong_dimension_count_exact_message(behaviors: dict[str, BehaviorDescriptor]) -> None:
    assert errors(behaviors["GO_TO_POINT"], coordinates=[1, 2]) == (
        "GO_TO_POINT: COORDINATES needs 3 numbers in [-100, 100], got 2",
    )


@pytest.mark.parametrize(
    ("value", "got"),
    [
        ([], "got 0"),
        ([1, 2, 3, 4], "got 4"),
        (5, "got 5"),  # a scalar where a vector is needed
        ("1,2,3", "got '1,2,3'"),
        ([1, "2", 3], "got [1, '2', 3]"),
        ([1, True, 3], "got [1, True, 3]"),
        ([0, 0, 100.5], "got [0, 0, 100.5] (100.5 is outside)"),
        ([-101, 0, 0], "got [-101, 0, 0] (-101 is outside)"),
    ],
)
def test_vector_problems(behaviors: dict[str, BehaviorDescriptor], value: Any, got: str) -> None:
    assert errors(behaviors["GO_TO_POINT"], coordinates=value) == (
        f"GO_TO_POINT: COORDINATES needs 3 numbers in [-100, 100], {got}",
    )


@pytest.mark.parametrize("value", [[-100, 0, 100], (3, 5.5, 1.3), [0.0, -0.0, 99.99]])
def test_vectors_within_bounds(behaviors: dict[str, BehaviorDescriptor], value: Any) -> None:
    check = check_arguments(behaviors["GO_TO_POINT"], {"coordinates": value})
    assert check.ok
    assert check.values == {"COORDINATES": list(value)}  # tuples come back as lists


# -- symbols and text ---------------------------------------------------------------------


@pytest.mark.parametrize("given", ["FORWARD", "forward", "Forward", "fOrWaRd"])
def test_symbols_are_case_insensitive_and_normalized(
    behaviors: dict[str, BehaviorDescriptor], given: str
) -> None:
    check = check_arguments(behaviors["START_MOVING"], {"direction": given})
    assert check.ok
    assert check.values == {"DIRECTION": "FORWARD"}  # the catalog's spelling


@pytest.mark.parametrize(("given", "shown"), [("sideways", "'sideways'"), (1, "1"), ("", "''")])
def test_unknown_symbol(behaviors: dict[str, BehaviorDescriptor], given: Any, shown: str) -> None:
    assert errors(behaviors["START_MOVING"], direction=given) == (
        "START_MOVING: DIRECTION needs one of BACKWARD, FORWARD, UP, DOWN, LEFT, RIGHT, "
        f"got {shown}",
    )


def test_symbols_differ_per_behavior(behaviors: dict[str, BehaviorDescriptor]) -> None:
    # FLIP says BACK/FRONT where START_MOVING says BACKWARD/FORWARD.
    assert check_arguments(behaviors["FLIP"], {"direction": "back"}).values == {"DIRECTION": "BACK"}
    assert not check_arguments(behaviors["FLIP"], {"direction": "BACKWARD"}).ok


def test_text(behaviors: dict[str, BehaviorDescriptor]) -> None:
    broadcast = behaviors["BROADCAST_MESSAGE"]
    assert check_arguments(broadcast, {"text": "hello, operator"}).values == {
        "TEXT": "hello, operator"
    }
    assert check_arguments(broadcast, {"TEXT": ""}).ok
    assert errors(broadcast, text=5) == ("BROADCAST_MESSAGE: TEXT needs text, got 5",)
    assert errors(broadcast, text=["a"]) == ("BROADCAST_MESSAGE: TEXT needs text, got ['a']",)


# -- names --------------------------------------------------------------------------------


def test_unknown_argument_names_the_known_ones(behaviors: dict[str, BehaviorDescriptor]) -> None:
    assert errors(behaviors["GO_TO_POINT"], speed=3) == (
        "GO_TO_POINT: unknown argument 'speed' (arguments: COORDINATES, RELATIVE_COORDINATES)",
    )
    assert errors(behaviors["TAKE_OFF"], altitude=1) == (
        "TAKE_OFF: unknown argument 'altitude' (arguments: none)",
    )


def test_names_are_case_insensitive(behaviors: dict[str, BehaviorDescriptor]) -> None:
    # Missions write lower case (Appendix C: relative_coordinates=[0,0,0.5]).
    check = check_arguments(behaviors["GO_TO_POINT"], {"relative_coordinates": [0, 0, 0.5]})
    assert check.ok
    assert check.values == {"RELATIVE_COORDINATES": [0, 0, 0.5]}
    lower = ArgumentSpec("coordinates", ArgumentKind.RANGE, -1.0, 1.0, 2)
    lowercase_catalog = BehaviorDescriptor("GO", 5.0, False, arguments=(lower,))
    assert check_arguments(lowercase_catalog, {"COORDINATES": [0, 1]}).values == {
        "coordinates": [0, 1]
    }


def test_same_argument_twice_in_different_case(behaviors: dict[str, BehaviorDescriptor]) -> None:
    check = check_arguments(behaviors["ROTATE"], {"angle": 10, "ANGLE": 20})
    assert not check.ok
    assert check.errors == ("ROTATE: ANGLE given twice",)
    assert check.values == {"ANGLE": 10}


def test_every_problem_is_reported_in_order(behaviors: dict[str, BehaviorDescriptor]) -> None:
    check = check_arguments(
        behaviors["START_MOVING"], {"speed": 31, "direction": "north", "height": 2}
    )
    assert check.errors == (
        "START_MOVING: SPEED needs a number in [0, 30], got 31 (31 is outside)",
        "START_MOVING: DIRECTION needs one of BACKWARD, FORWARD, UP, DOWN, LEFT, RIGHT, "
        "got 'north'",
        "START_MOVING: unknown argument 'height' (arguments: SPEED, DIRECTION)",
    )


def test_no_arguments_is_valid(behaviors: dict[str, BehaviorDescriptor]) -> None:
    check = check_arguments(behaviors["GO_TO_POINT"], {})
    assert check.ok and check.values == {}


def test_check_value_reports_malformed_specs() -> None:
    invalid = ArgumentSpec("X", ArgumentKind.INVALID)
    error, value = check_value("B", invalid, 3)
    assert error == "B: X has a malformed specification in the catalog"
    assert value == 3


def test_unbounded_range_accepts_any_finite_number() -> None:
    spec = ArgumentSpec("X", ArgumentKind.RANGE, -math.inf, math.inf)
    assert check_value("B", spec, -1e300) == (None, -1e300)
    assert check_value("B", spec, math.nan)[0] is not None
