"""The catalog loader: the thesis' Appendix A catalog, tag classes, dialects, marks.

Expected values come from the thesis text (Appendix A, section 3.3.1) and
docs/design.md#catalogs, not from the loader; positions are found by searching the YAML
text, so a wrong `file:line:col` fails here.
"""

from __future__ import annotations

import dataclasses
import textwrap
import time
from typing import Any

import pytest
import yaml

from aeroexec.catalog import (
    THESIS_CATALOG,
    ArgumentKind,
    Catalog,
    Diagnostic,
    Severity,
    check_arguments,
    codes,
    load_catalog,
    parse_catalog,
    read_catalog,
    strict,
    yamlnodes,
)
from aeroexec.catalog.model import IN_MEMORY
from aeroexec.errors import CatalogError, Mark

# -- helpers ------------------------------------------------------------------------------


def where(text: str, needle: str, nth: int = 0) -> tuple[int, int]:
    """1-based (line, column) of the nth occurrence of `needle` in `text`."""
    index = -1
    for _ in range(nth + 1):
        index = text.index(needle, index + 1)
    line = text.count("\n", 0, index) + 1
    return line, index - (text.rfind("\n", 0, index) + 1) + 1


def at(mark: Mark) -> tuple[int, int]:
    return mark.line, mark.column


def doc(text: str) -> str:
    return textwrap.dedent(text).lstrip("\n")


def only(catalog: Catalog, code: str) -> list[Diagnostic]:
    return [d for d in catalog.diagnostics if d.code == code]


#: A complete, clean thesis-dialect catalog that tests vary one tag at a time.
BASE = doc(
    """
    behavior_descriptors:
      - behavior: GO
        timeout: 30
        recurrent: no
        incompatible_lists: [moves]
        capabilities: [FLIGHT]
        arguments:
          - argument: COORDINATES
            allowed_values: [-10, 10]
            dimensions: 3
    behavior_lists:
      - list: moves
        behaviors: [GO]
    capability_descriptors:
      - capability: FLIGHT
        active_by_default: no
        processes: [controller]
        incompatible_capabilities: []
    """
)


# -- the thesis' Appendix A catalog ------------------------------------------------------

MOTION_AND_ROTATION = ("motion_behaviors", "rotation_behaviors")
SBFC = "SETPOINT_BASED_FLIGHT_CONTROL"
#: Appendix A, in file order: name, timeout (s), recurrent, incompatible lists, capabilities.
THESIS_BEHAVIORS: list[tuple[str, float | None, bool, tuple[str, ...], tuple[str, ...]]] = [
    ("TAKE_OFF", 15, False, MOTION_AND_ROTATION, ()),
    ("LAND", 15, False, MOTION_AND_ROTATION, ()),
    ("GO_TO_POINT", 120, False, MOTION_AND_ROTATION, (SBFC, "PATH_PLANNING")),
    ("ROTATE", 15, False, MOTION_AND_ROTATION, (SBFC,)),
    ("START_MOVING", 15, False, MOTION_AND_ROTATION, (SBFC,)),
    ("FOLLOW_OBJECT_IMAGE", 90, False, MOTION_AND_ROTATION, ("VISUAL_SERVOING",)),
    # No timeout in the thesis: a recurrent behavior runs until inhibited.
    ("PAY_ATTENTION", None, True, (), ("VISUAL_MARKERS_RECOGNITION",)),
    ("KEEP_HOVERING", 15, False, MOTION_AND_ROTATION, (SBFC,)),
    ("WAIT", 15, False, (), ()),
    ("FLIP", 15, False, MOTION_AND_ROTATION, (SBFC,)),
    ("START_HOVERING", 15, False, MOTION_AND_ROTATION, (SBFC,)),
    ("BROADCAST_MESSAGE", 15, False, (), ()),
]
R, S, T = ArgumentKind.RANGE, ArgumentKind.SYMBOLS, ArgumentKind.TEXT
#: name, kind, minimum, maximum, dimensions, symbols
THESIS_ARGUMENTS: dict[str, list[tuple[Any, ...]]] = {
    "GO_TO_POINT": [
        ("COORDINATES", R, -100, 100, 3, ()),
        ("RELATIVE_COORDINATES", R, -100, 100, 3, ()),
    ],
    "ROTATE": [("ANGLE", R, -360, 360, 1, ())],
    "START_MOVING": [
        ("SPEED", R, 0, 30, 1, ()),
        ("DIRECTION", S, None, None, 1, ("BACKWARD", "FORWARD", "UP", "DOWN", "LEFT", "RIGHT")),
    ],
    "KEEP_HOVERING": [("DURATION", R, 1, 1000, 1, ()), ("ARUCO", R, 0, 1023, 1, ())],
    "WAIT": [
        ("DURATION", R, 1, 1000, 1, ()),
        ("UNTIL_OBSERVED_VISUAL_MARKER", R, 0, 1023, 1, ()),
    ],
    "FLIP": [("DIRECTION", S, None, None, 1, ("BACK", "FRONT", "LEFT", "RIGHT"))],
    "BROADCAST_MESSAGE": [("TEXT", T, None, None, 1, ())],
}
THESIS_LISTS = {
    "motion_behaviors": (
        "TAKE_OFF",
        "LAND",
        "FLIP",
        "KEEP_HOVERING",
        "FOLLOW_OBJECT_IMAGE",
        "START_MOVING",
        "START_HOVERING",
        "GO_TO_POINT",
        "VISUAL_SERVOING",  # a capability, listed as a behavior in the thesis
    ),
    "rotation_behaviors": ("ROTATE", "LOOK_AT_POINT"),  # LOOK_AT_POINT is never defined
}
#: name, processes (start order), active_by_default, incompatible_capabilities
THESIS_CAPABILITIES = [
    (SBFC, ("droneTrajectoryController",), False, ("VISUAL_SERVOING",)),
    ("PATH_PLANNING", ("droneTrajectoryPlanner", "droneYawPlanner"), False, ()),
    (
        "VISUAL_SERVOING",
        ("trackerEye", "open_tld_translator", "droneIBVSController"),
        False,
        (SBFC,),
    ),
    ("SELF_LOCALIZATION_BY_ODOMETRY", ("droneOdometryStateEstimator",), True, ()),
    (
        "SELF_LOCALIZATION_BY_VISUAL_MARKERS",
        ("droneLocalizer", "droneObstacleDistanceCalculator", "droneObstacleProcessor"),
        False,
        (),
    ),
    ("VISUAL_MARKERS_RECOGNITION", ("droneArucoEyeROSModule",), False, ()),
]


def test_thesis_behaviors_in_file_order(thesis_catalog: Catalog) -> None:
    got = [
        (b.name, b.timeout, b.recurrent, b.incompatible_lists, b.capabilities)
        for b in thesis_catalog.behaviors.values()
    ]
    assert got == THESIS_BEHAVIORS


@pytest.mark.parametrize("behavior", [b[0] for b in THESIS_BEHAVIORS])
def test_thesis_arguments(thesis_catalog: Catalog, behavior: str) -> None:
    got = [
        (a.name, a.kind, a.minimum, a.maximum, a.dimensions, a.symbols)
        for a in thesis_catalog.behaviors[behavior].arguments
    ]
    assert got == THESIS_ARGUMENTS.get(behavior, [])


def test_thesis_lists(thesis_catalog: Catalog) -> None:
    assert {n: lst.behaviors for n, lst in thesis_catalog.lists.items()} == THESIS_LISTS
    assert list(thesis_catalog.lists) == list(THESIS_LISTS)


def test_thesis_capabilities(thesis_catalog: Catalog) -> None:
    got = [
        (c.name, c.processes, c.active_by_default, c.incompatible_capabilities)
        for c in thesis_catalog.capabilities.values()
    ]
    assert got == THESIS_CAPABILITIES
    assert all(c.required_capabilities == () for c in thesis_catalog.capabilities.values())


def test_thesis_indexes(thesis_catalog: Catalog) -> None:
    c = thesis_catalog
    every_mover = set(THESIS_LISTS["motion_behaviors"]) | set(THESIS_LISTS["rotation_behaviors"])
    for name, _, _, lists, _ in THESIS_BEHAVIORS:
        assert c.preempted_by(name) == (every_mover if lists else frozenset()), name
    assert c.preempted_by("NO_SUCH_BEHAVIOR") == frozenset()
    # Conflicts are symmetric even where only one side declares them.
    assert c.conflicts_of(SBFC) == {"VISUAL_SERVOING"}
    assert c.conflicts_of("VISUAL_SERVOING") == {SBFC}
    assert c.conflicts_of("PATH_PLANNING") == frozenset()
    assert c.conflicts_of("NO_SUCH_CAPABILITY") == frozenset()
    assert c.default_capabilities == ("SELF_LOCALIZATION_BY_ODOMETRY",)
    assert [c.order_of(b[0]) for b in THESIS_BEHAVIORS] == list(range(12))
    assert c.order_of("NO_SUCH_BEHAVIOR") == 12  # unknown names sort last


def test_thesis_conflicts_declared_one_way_are_symmetric() -> None:
    text = BASE + "  - capability: CAMERA\n    processes: [cam]\n    active_by_default: no\n"
    text = text.replace("incompatible_capabilities: []", "incompatible_capabilities: [CAMERA]")
    catalog = parse_catalog(text)
    assert catalog.conflicts_of("CAMERA") == {"FLIGHT"}
    assert catalog.conflicts_of("FLIGHT") == {"CAMERA"}


def test_thesis_diagnostics_and_marks(thesis_catalog: Catalog) -> None:
    text = THESIS_CATALOG.read_text(encoding="utf-8")
    assert thesis_catalog.dialect == "thesis-2017"
    assert thesis_catalog.source == str(THESIS_CATALOG)
    assert not [d for d in thesis_catalog.diagnostics if d.severity is Severity.ERROR]
    warnings = [
        (d.code, at(d.mark)) for d in thesis_catalog.warnings() if d.severity.value == "warning"
    ]
    # The two capabilities the thesis gives no active_by_default.
    assert warnings == [
        ("AX102", where(text, "capability: SELF_LOCALIZATION_BY_VISUAL_MARKERS")),
        ("AX102", where(text, "capability: VISUAL_MARKERS_RECOGNITION")),
    ]
    # A mark points at the mapping (after "- "), where editors put the cursor.
    for behavior in thesis_catalog.behaviors.values():
        line, column = where(text, f"- behavior: {behavior.name}\n")
        assert at(behavior.mark) == (line, column + 2), behavior.name
    go = thesis_catalog.behaviors["GO_TO_POINT"]
    assert at(go.mark_of("capabilities.1")) == where(text, "PATH_PLANNING]")
    assert at(go.mark_of("timeout")) == where(text, "timeout: 120")
    assert at(go.arguments[1].mark) == where(text, "argument: RELATIVE_COORDINATES")
    assert at(thesis_catalog.lists["rotation_behaviors"].mark_of("behaviors.1")) == where(
        text, "LOOK_AT_POINT]"
    )
    assert at(thesis_catalog.section_marks["capability_descriptors"]) == where(
        text, "capability_descriptors:"
    )


def test_thesis_duplicates_none(thesis_catalog: Catalog) -> None:
    assert len(thesis_catalog.all_behaviors) == len(thesis_catalog.behaviors) == 12
    assert len(thesis_catalog.all_capabilities) == 6


def test_thesis_arguments_are_usable(thesis_catalog: Catalog) -> None:
    """The catalog's specs drive check_arguments (the mission in Appendix C calls these)."""
    go = thesis_catalog.behaviors["GO_TO_POINT"]
    assert check_arguments(go, {"relative_coordinates": [0, 0, 0.5]}).ok
    assert check_arguments(thesis_catalog.behaviors["ROTATE"], {"angle": -90}).ok
    assert not check_arguments(thesis_catalog.behaviors["ROTATE"], {"angle": 361}).ok


# -- the pure-Python YAML fallback --------------------------------------------------------


def _strip(catalog: Catalog) -> tuple[Any, ...]:
    return (
        list(catalog.behaviors.values()),
        list(catalog.lists.values()),
        list(catalog.capabilities.values()),
        catalog.diagnostics,
        catalog.dialect,
        [dict(b.marks) for b in catalog.behaviors.values()],
    )


@pytest.mark.skipif(not yamlnodes.HAS_C_LOADER, reason="PyYAML built without libyaml")
def test_pure_python_loader_gives_the_same_catalog(monkeypatch: pytest.MonkeyPatch) -> None:
    with_c = read_catalog(THESIS_CATALOG)
    monkeypatch.setattr(yamlnodes, "_Loader", yaml.SafeLoader)
    pure = read_catalog(THESIS_CATALOG)
    assert _strip(pure) == _strip(with_c)
    assert len(pure.behaviors) == 12  # not vacuously equal


def test_pure_python_loader_reports_errors_at_the_same_place(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # A control character after non-ASCII text: libyaml reports a byte offset, Python's
    # reader a character offset; both must come out as the same line:col.
    text = 'behavior_descriptors: []\nname: "héllo wörld\x07"\n'
    expected = where(text, "\x07")
    results = []
    for loader in {yamlnodes._Loader, yaml.SafeLoader}:
        monkeypatch.setattr(yamlnodes, "_Loader", loader)
        with pytest.raises(CatalogError) as err:
            parse_catalog(text, "f.yaml")
        assert err.value.mark is not None
        assert at(err.value.mark) == expected
        assert "#x0007" in err.value.message
        results.append(str(err.value).splitlines())
    assert all(len(lines) == 1 for lines in results)


# -- warning tags (default applied + warning) ---------------------------------------------


def test_missing_timeout_gets_15_s_and_a_warning() -> None:
    text = BASE.replace("    timeout: 30\n", "")
    catalog = parse_catalog(text, "c.yaml")
    assert catalog.behaviors["GO"].timeout == 15.0
    (warning,) = only(catalog, codes.MISSING_WARNING_TAG)
    assert warning.severity is Severity.WARNING
    assert at(warning.mark) == where(text, "behavior: GO")
    assert "no timeout" in warning.message and "15 s" in warning.message
    assert warning.subjects == ("GO",)


def test_missing_recurrent_means_goal_based_with_a_warning() -> None:
    text = BASE.replace("    recurrent: no\n", "")
    catalog = parse_catalog(text)
    assert catalog.behaviors["GO"].recurrent is False
    (warning,) = only(catalog, codes.MISSING_WARNING_TAG)
    assert "recurrent" in warning.message and "goal-based" in warning.message


def test_recurrent_behavior_needs_no_timeout() -> None:
    text = BASE.replace("    timeout: 30\n    recurrent: no\n", "    recurrent: yes\n")
    catalog = parse_catalog(text)
    assert catalog.behaviors["GO"].recurrent is True
    assert catalog.behaviors["GO"].timeout is None
    assert only(catalog, codes.MISSING_WARNING_TAG) == []


def test_missing_active_by_default_means_no_with_a_warning() -> None:
    text = BASE.replace("    active_by_default: no\n", "")
    catalog = parse_catalog(text)
    assert catalog.capabilities["FLIGHT"].active_by_default is False
    (warning,) = only(catalog, codes.MISSING_WARNING_TAG)
    assert "active_by_default" in warning.message
    assert at(warning.mark) == where(text, "capability: FLIGHT")


def test_activate_by_default_is_accepted_with_a_warning() -> None:
    # The thesis' own text spells the tag `activate_by_default`.
    text = BASE.replace("active_by_default: no", "activate_by_default: yes")
    catalog = parse_catalog(text)
    assert catalog.capabilities["FLIGHT"].active_by_default is True
    assert catalog.default_capabilities == ("FLIGHT",)
    (warning,) = only(catalog, codes.UNKNOWN_TAG)
    assert warning.severity is Severity.WARNING
    assert "'activate_by_default'" in warning.message
    assert "'active_by_default'" in warning.message
    assert at(warning.mark) == where(text, "activate_by_default")
    assert only(catalog, codes.MISSING_WARNING_TAG) == []


@pytest.mark.parametrize(
    ("value", "expected"),
    [("yes", True), ("no", False), ("true", True), ("False", False), ("on", True), ("n", False)],
)
def test_yes_no_spellings(value: str, expected: bool) -> None:
    catalog = parse_catalog(BASE.replace("active_by_default: no", f"active_by_default: {value}"))
    assert catalog.capabilities["FLIGHT"].active_by_default is expected
    assert not [d for d in catalog.diagnostics if d.severity is Severity.ERROR]


# -- unknown tags (did you mean) ----------------------------------------------------------


@pytest.mark.parametrize(
    ("old", "new", "suggestion"),
    [
        ("    timeout: 30", "    timeot: 30", "timeout"),
        ("    incompatible_lists:", "    incompatible_list:", "incompatible_lists"),
        ("behavior_lists:", "behaviour_lists:", "behavior_lists"),
        ("        dimensions: 3", "        dimension: 3", "dimensions"),
        (
            "    incompatible_capabilities: []",
            "    incompatible_capability: []",
            "incompatible_capabilities",
        ),
    ],
)
def test_unknown_tag_says_did_you_mean(old: str, new: str, suggestion: str) -> None:
    text = BASE.replace(old, new)
    catalog = parse_catalog(text)
    unknown = only(catalog, codes.UNKNOWN_TAG)
    key = new.strip().split(":")[0]
    assert len(unknown) == 1
    assert f"unknown tag '{key}'" in unknown[0].message
    assert at(unknown[0].mark) == where(text, key)
    assert unknown[0].message.endswith(f"(did you mean '{suggestion}'?)")


def test_unknown_tag_without_close_match_has_no_suggestion() -> None:
    catalog = parse_catalog(BASE.replace("    timeout: 30", "    colour: blue\n    timeout: 30"))
    (unknown,) = only(catalog, codes.UNKNOWN_TAG)
    assert unknown.message == "unknown tag 'colour' in behavior GO"


# -- dependency tags (info when absent) ---------------------------------------------------


def test_absent_dependency_tags_give_infos() -> None:
    text = doc(
        """
        behavior_descriptors:
          - behavior: HOVER
            timeout: 10
            recurrent: no
        capability_descriptors:
          - capability: CAM
            active_by_default: no
            processes: [cam]
        """
    )
    catalog = parse_catalog(text)
    infos = only(catalog, codes.MISSING_DEPENDENCY_TAG)
    assert all(d.severity is Severity.INFO for d in infos)
    assert sorted(d.message for d in infos) == [
        "HOVER: no arguments; none is assumed",
        "HOVER: no capabilities; none is assumed",
        "HOVER: no incompatible_lists; none is assumed",
        "capability CAM: no incompatible_capabilities; none is assumed",
    ]
    hover = catalog.behaviors["HOVER"]
    assert (hover.incompatible_lists, hover.capabilities, hover.arguments) == ((), (), ())
    assert catalog.capabilities["CAM"].incompatible_capabilities == ()
    assert strict(catalog) is catalog  # infos never stop loading


def test_written_dependency_tags_give_no_info() -> None:
    catalog = parse_catalog(BASE)
    assert only(catalog, codes.MISSING_DEPENDENCY_TAG) == []
    # Written but empty (`capabilities:` with no value) is written: no info either.
    emptied = BASE.replace("capabilities: [FLIGHT]", "capabilities:")
    assert only(parse_catalog(emptied), codes.MISSING_DEPENDENCY_TAG) == []
    assert parse_catalog(emptied).behaviors["GO"].capabilities == ()


def test_single_name_instead_of_a_list_is_read_as_one_with_a_warning() -> None:
    text = BASE.replace("[moves]", "moves")
    catalog = parse_catalog(text)
    assert catalog.behaviors["GO"].incompatible_lists == ("moves",)
    [warning] = only(catalog, codes.SCALAR_FOR_LIST)
    assert warning.severity is Severity.WARNING
    assert at(warning.mark) == where(text, "moves")
    assert "iterated it as an empty list; write [moves]" in warning.message


def test_boolean_words_are_symbols_the_mission_and_executive_accept() -> None:
    text = SPEC.replace("{spec}", "        allowed_values: [ON, OFF]")
    catalog = strict(parse_catalog(text))
    behavior = catalog.behaviors["B"]
    assert check_arguments(behavior, {"x": "on"}).values == {"X": "ON"}
    assert check_arguments(behavior, {"X": True}).errors


def test_reference_through_an_alias_is_marked_where_it_is_used() -> None:
    text = doc(
        """
        behavior_descriptors:
          - behavior: GO
            timeout: 30
            recurrent: no
            incompatible_lists: [&typo mvoes]
          - behavior: TURN
            timeout: 30
            recurrent: no
            incompatible_lists: [*typo]
        behavior_lists:
          - list: moves
            behaviors: [GO, TURN]
        capability_descriptors: []
        """
    )
    catalog = parse_catalog(text)
    assert at(catalog.behaviors["TURN"].mark_of("incompatible_lists.0")) == where(text, "*typo")
    assert at(catalog.behaviors["GO"].mark_of("incompatible_lists.0")) == where(text, "&typo")


@pytest.mark.parametrize("value", [".inf", "1.0e+300", "1.0e+10"])
def test_timeout_the_executive_cannot_arm_is_an_error(value: str) -> None:
    text = BASE.replace("timeout: 30", f"timeout: {value}")
    catalog = parse_catalog(text)
    [error] = [d for d in catalog.diagnostics if d.severity is Severity.ERROR]
    assert error.code == codes.WRONG_TYPE
    assert at(error.mark) == where(text, value)
    assert "at most 9.22e+09 s" in error.message
    with pytest.raises(CatalogError):
        strict(catalog)


def test_longest_timeout_the_executive_arms_is_accepted() -> None:
    catalog = strict(parse_catalog(BASE.replace("timeout: 30", "timeout: 9.2e+9")))
    assert catalog.behaviors["GO"].timeout == 9.2e9


# -- error tags ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("old", "new", "needle", "message"),
    [
        (
            "behavior_descriptors:",
            "behaviors_descriptors:",
            "behaviors_descriptors",
            "missing 'behavior_descriptors'",
        ),
        (
            "capability_descriptors:",
            "capabilities_descriptors:",
            "behavior_descriptors",  # reported at the document's first key
            "missing 'capability_descriptors'",
        ),
        (
            "- behavior: GO",
            "- behaviour: GO",
            "behaviour: GO",
            "a behavior descriptor has no 'behavior' (an error tag); found 'behaviour'",
        ),
        ("- list: moves", "- name: moves", "name: moves", "a behavior list has no 'list'"),
        (
            "    behaviors: [GO]",
            "    members: [GO]",
            "list: moves",
            "list moves has no 'behaviors' (an error tag)",
        ),
        (
            "- capability: FLIGHT",
            "- capabilty: FLIGHT",
            "capabilty: FLIGHT",
            "a capability descriptor has no 'capability' (an error tag); found 'capabilty'",
        ),
        (
            "    processes: [controller]",
            "    proceses: [controller]",
            "capability: FLIGHT",
            "capability FLIGHT has no 'processes' (an error tag)",
        ),
    ],
)
def test_missing_error_tag(old: str, new: str, needle: str, message: str) -> None:
    text = BASE.replace(old, new)
    catalog = parse_catalog(text, "c.yaml")
    errors = [d for d in catalog.diagnostics if d.severity is Severity.ERROR]
    assert [d.code for d in errors] == [codes.MISSING_ERROR_TAG]
    assert message in errors[0].message
    assert at(errors[0].mark) == where(text, needle)
    # load_catalog is strict: the same problem is a CatalogError at the same place.
    with pytest.raises(CatalogError) as err:
        strict(catalog)
    assert err.value.mark == errors[0].mark
    assert err.value.message.endswith(f"[{codes.MISSING_ERROR_TAG}]")


def test_load_catalog_is_strict_and_read_catalog_lenient(tmp_path: Any) -> None:
    path = tmp_path / "c.yaml"
    path.write_text(BASE.replace("    processes: [controller]\n", ""), encoding="utf-8")
    lenient = read_catalog(path)
    assert "FLIGHT" not in lenient.capabilities  # dropped, the rest is kept
    assert "GO" in lenient.behaviors
    with pytest.raises(CatalogError, match=r"capability FLIGHT has no 'processes'"):
        load_catalog(path)


# -- wrong types (AX105) ------------------------------------------------------------------


@pytest.mark.parametrize(
    ("old", "new", "needle", "message"),
    [
        (
            "timeout: 30",
            "timeout: fast",
            "fast",
            "GO: timeout must be a positive number of seconds, got str ('fast')",
        ),
        (
            "timeout: 30",
            "timeout: 0",
            "0\n",
            "GO: timeout must be a positive number of seconds, got int (0)",
        ),
        (
            "timeout: 30",
            "timeout: yes",
            "yes",
            "GO: timeout must be a positive number of seconds, got bool (True)",
        ),
        (
            "timeout: 30",
            "timeout: " + "9" * 400,
            "9999",
            "GO: timeout must be a positive number of seconds, got int",
        ),
        ("recurrent: no", "recurrent: maybe", "maybe", "GO: recurrent must be yes or no"),
        (
            "incompatible_lists: [moves]",
            "incompatible_lists: {a: 1}",
            "{a: 1}",
            "GO: incompatible_lists must be a list of names, got mapping",
        ),
        (
            "capabilities: [FLIGHT]",
            "capabilities: [[FLIGHT]]",
            "[FLIGHT]]",
            "an entry of GO: capabilities must be a name, got list",
        ),
        (
            "behaviors: [GO]",
            "behaviors: [~]",
            "~",
            "an entry of list moves: behaviors must be a name, got null",
        ),
        (
            "active_by_default: no",
            "active_by_default: 2",
            "2\n",
            "capability FLIGHT: active_by_default must be yes or no, got int (2)",
        ),
    ],
)
def test_wrong_type(old: str, new: str, needle: str, message: str) -> None:
    text = BASE.replace(old, new)
    catalog = parse_catalog(text)
    errors = [d for d in catalog.diagnostics if d.severity is Severity.ERROR]
    assert [d.code for d in errors] == [codes.WRONG_TYPE]
    assert errors[0].message.startswith(message)
    assert at(errors[0].mark) == where(text, needle)


@pytest.mark.parametrize(
    ("old", "new", "shown"),
    [
        ("timeout: 30", "timeout: " + "x" * 100_000, "got str ('" + "x" * 40 + "...')"),
        ("timeout: 30", "timeout: " + "9" * 4000, "got int (" + "9" * 40 + "...)"),
    ],
)
def test_a_huge_wrong_value_is_shown_cut_short(old: str, new: str, shown: str) -> None:
    # Issue 23's hostile files: a 100 KB word where a number belongs was echoed whole,
    # one 100 KB line per finding; the place already says where the rest is.
    catalog = parse_catalog(BASE.replace(old, new))
    (error,) = [d for d in catalog.diagnostics if d.severity is Severity.ERROR]
    assert error.message.endswith(shown) and len(error.message) < 200, error.message[:300]


def test_section_of_the_wrong_shape() -> None:
    text = "behavior_descriptors: 5\ncapability_descriptors:\n  - just a name\n"
    catalog = parse_catalog(text)
    assert [
        (d.code, at(d.mark), d.message) for d in catalog.diagnostics if d.severity.value == "error"
    ] == [
        (codes.WRONG_TYPE, (1, 23), "behavior_descriptors must be a list, got int (5)"),
        (
            codes.WRONG_TYPE,
            (3, 5),
            "each entry of capability_descriptors must be a mapping, got str ('just a name')",
        ),
    ]


# -- the Aerostack 2.x dialect ------------------------------------------------------------

THESIS_DIALECT = doc(
    """
    behavior_descriptors:
      - behavior: A
        timeout: 15
        recurrent: no
        incompatible_lists: [L]
        capabilities: [C1, C2]
      - behavior: B
        recurrent: yes
        capabilities: [C2]
    behavior_lists:
      - list: L
        behaviors: [A, B]
    capability_descriptors:
      - capability: C1
        active_by_default: no
        processes: [p1, p2]
        incompatible_capabilities: [C2]
      - capability: C2
        active_by_default: no
        processes: [p3]
    """
)
FLOWN_DIALECT = doc(
    """
    default_behavior_values:
      timeout: 15
      category: goal_based
    behavior_descriptors:
      - behavior: A
        incompatible_lists: [L]
        capabilities: [C1, C2]
      - behavior: B
        category: recurrent
        capabilities: [C2]
    behavior_lists:
      - list: L
        behaviors: [A, B]
    capability_descriptors:
      - capability: C1
        process_sequence: [p1, p2]
        incompatible_capabilities: [C2]
      - capability: C2
        process_sequence: [p3]
    """
)


def _unmarked(catalog: Catalog) -> tuple[Any, ...]:
    def plain(item: Any) -> Any:
        changes: dict[str, Any] = {"mark": IN_MEMORY}
        if hasattr(item, "arguments"):
            changes["arguments"] = tuple(
                dataclasses.replace(a, mark=IN_MEMORY) for a in item.arguments
            )
        return dataclasses.replace(item, **changes)

    return (
        [plain(b) for b in catalog.behaviors.values()],
        [plain(x) for x in catalog.lists.values()],
        [plain(c) for c in catalog.capabilities.values()],
    )


def test_both_dialects_read_into_the_same_model() -> None:
    thesis = parse_catalog(THESIS_DIALECT)
    flown = parse_catalog(FLOWN_DIALECT)
    assert thesis.dialect == "thesis-2017"
    assert flown.dialect == "aerostack-2.x"
    assert _unmarked(flown) == _unmarked(thesis)
    assert flown.behaviors["B"].recurrent is True and flown.behaviors["B"].timeout is None
    assert flown.capabilities["C1"].processes == ("p1", "p2")
    assert flown.preempted_by("A") == thesis.preempted_by("A") == {"A", "B"}
    # The 2.x format has no active_by_default and relies on its defaults: no warnings.
    assert [d for d in flown.diagnostics if d.severity is not Severity.INFO] == []
    (dialect,) = only(flown, codes.DIALECT)
    assert "Aerostack 2.x" in dialect.message


def test_default_behavior_values_apply_to_behaviors_without_tags() -> None:
    text = FLOWN_DIALECT.replace("category: goal_based", "category: recurrent")
    assert text != FLOWN_DIALECT
    catalog = parse_catalog(text)
    # A has no category: recurrent from the block, and recurrent behaviors get no timeout.
    assert (catalog.behaviors["A"].recurrent, catalog.behaviors["A"].timeout) == (True, None)
    text = FLOWN_DIALECT.replace("timeout: 15", "timeout: 40")
    catalog = parse_catalog(text)
    assert catalog.behaviors["A"].timeout == 40.0
    assert catalog.behaviors["A"].recurrent is False


def test_flown_catalog_without_category_is_goal_based_with_the_default_timeout() -> None:
    # NOTES.md section 2: SELF_LOCALIZE_BY_ODOMETRY in drone2/drone4 has no category.
    text = FLOWN_DIALECT.replace("    category: recurrent\n", "")
    catalog = parse_catalog(text)
    assert (catalog.behaviors["B"].recurrent, catalog.behaviors["B"].timeout) == (False, 15.0)
    assert only(catalog, codes.MISSING_WARNING_TAG) == []  # the block said so explicitly


def test_required_and_incompatible_capabilities_are_read() -> None:
    text = FLOWN_DIALECT.replace(
        "    process_sequence: [p3]\n",
        "    process_sequence: [p3]\n    required_capabilities: [C1, MISSING]\n",
    )
    catalog = parse_catalog(text)
    c2 = catalog.capabilities["C2"]
    assert c2.required_capabilities == ("C1", "MISSING")  # dangling: the verifier's job
    assert at(c2.mark_of("required_capabilities.1")) == where(text, "MISSING")
    assert catalog.capabilities["C1"].incompatible_capabilities == ("C2",)


def test_mixed_dialect_is_named() -> None:
    text = FLOWN_DIALECT.replace("category: recurrent", "recurrent: yes")
    assert parse_catalog(text).dialect == "mixed"


def test_reactive_activation_is_an_ignored_section() -> None:
    text = FLOWN_DIALECT + "reactive_activation:\n  - behavior: A\n    condition: x\n"
    catalog = parse_catalog(text)
    (info,) = only(catalog, codes.IGNORED_SECTION)
    assert info.severity is Severity.INFO
    assert at(info.mark) == where(text, "reactive_activation")


def test_bad_default_behavior_values() -> None:
    text = FLOWN_DIALECT.replace("category: goal_based", "category: sometimes")
    catalog = parse_catalog(text)
    errors = [d for d in catalog.diagnostics if d.severity is Severity.ERROR]
    assert [(d.code, at(d.mark)) for d in errors] == [(codes.WRONG_TYPE, where(text, "sometimes"))]
    assert "goal_based or recurrent" in errors[0].message


def test_task_format_is_refused_naming_it() -> None:
    text = "default_values:\n  timeout: 15\nbehaviors:\n  - behavior: X\ntasks:\n  - task: T\n"
    with pytest.raises(CatalogError) as err:
        parse_catalog(text, "tasks.yaml")
    assert "Aerostack 4.x task-based catalog" in err.value.message
    assert err.value.mark == Mark("tasks.yaml", 1, 1)


# -- duplicates ---------------------------------------------------------------------------


def test_duplicate_key_keeps_the_last_value_with_a_warning() -> None:
    text = BASE.replace("    timeout: 30\n", "    timeout: 30\n    timeout: 45\n")
    catalog = parse_catalog(text)
    assert catalog.behaviors["GO"].timeout == 45.0
    (dup,) = only(catalog, codes.DUPLICATE_KEY)
    assert dup.severity is Severity.WARNING
    assert at(dup.mark) == where(text, "timeout: 45")
    assert "'timeout'" in dup.message


def test_duplicate_behavior_later_definition_wins() -> None:
    text = BASE.replace(
        "behavior_lists:",
        "  - behavior: GO\n    timeout: 99\n    recurrent: no\nbehavior_lists:",
    )
    catalog = parse_catalog(text)
    assert catalog.behaviors["GO"].timeout == 99.0
    assert [b.timeout for b in catalog.all_behaviors] == [30.0, 99.0]
    (dup,) = only(catalog, codes.DUPLICATE_DEFINITION)
    assert at(dup.mark) == where(text, "behavior: GO", nth=1)
    assert f"first at line {where(text, 'behavior: GO')[0]}" in dup.message


def test_duplicate_capability_and_list_are_reported() -> None:
    text = (
        BASE.replace(
            "capability_descriptors:",
            "  - list: moves\n    behaviors: []\ncapability_descriptors:",
        )
        + "  - capability: FLIGHT\n    processes: [other]\n    active_by_default: yes\n"
    )
    catalog = parse_catalog(text)
    assert sorted(d.message.split()[0] for d in only(catalog, codes.DUPLICATE_DEFINITION)) == [
        "capability",
        "list",
    ]
    assert catalog.lists["moves"].behaviors == ()
    assert catalog.capabilities["FLIGHT"].processes == ("other",)


# -- malformed argument specs (AX108) -----------------------------------------------------

SPEC = doc(
    """
    behavior_descriptors:
      - behavior: B
        timeout: 5
        recurrent: no
        arguments:
          - argument: X
    {spec}
    capability_descriptors: []
    """
)


@pytest.mark.parametrize(
    ("spec", "needle", "message"),
    [
        ("", "argument: X", "no allowed_values"),
        ("        allowed_values: 5", "5\n", "allowed_values must be [min, max]"),
        ("        allowed_values: text", "text", "allowed_values must be [min, max]"),
        ("        allowed_values: []", "[]", "allowed_values must be [min, max]"),
        ("        allowed_values: [1, 2, 3]", "[1, 2, 3]", "a numeric range is [min, max], got 3"),
        ("        allowed_values: [1]", "[1]", "a numeric range is [min, max], got 1"),
        ("        allowed_values: [10, 1]", "[10, 1]", "empty range [10, 1] (min > max)"),
        ("        allowed_values: [1, UP]", "[1, UP]", "allowed_values mixes numbers and symbols"),
        ("        allowed_values: [UP, UP]", "[UP, UP]", "a symbol is listed twice"),
        (
            "        allowed_values: [UP, DOWN]\n        dimensions: 2",
            "argument: X",
            "dimensions applies only to numeric ranges",
        ),
        (
            "        allowed_values: [0, 1]\n        dimensions: 0",
            "0\n",
            "dimensions must be a whole number >= 1, got int (0)",
        ),
        (
            "        allowed_values: [0, 1]\n        dimensions: 2.5",
            "2.5",
            "dimensions must be a whole number >= 1, got float (2.5)",
        ),
        (
            "        allowed_values: [0, 1]\n        dimensions: yes",
            "yes",
            "dimensions must be a whole number >= 1, got bool (True)",
        ),
        ("        allowed_values: [.nan, 1]", "[.nan", "NaN or too large"),
        ("        allowed_values: [0, " + "9" * 400 + "]", "[0,", "NaN or too large"),
        ("        allowed_values: [1, ON]", "[1, ON]", "allowed_values mixes numbers and symbols"),
    ],
)
def test_malformed_argument_spec(spec: str, needle: str, message: str) -> None:
    text = SPEC.replace("{spec}\n", spec + "\n" if spec else "")
    catalog = parse_catalog(text)
    errors = [d for d in catalog.diagnostics if d.severity is Severity.ERROR]
    assert [d.code for d in errors] == [codes.MALFORMED_ARGUMENT], errors
    assert errors[0].message.startswith("B: argument X: ")
    assert message in errors[0].message
    assert at(errors[0].mark) == where(text, needle, nth=1 if needle == "5\n" else 0)
    (spec_obj,) = catalog.behaviors["B"].arguments
    assert spec_obj.kind is ArgumentKind.INVALID
    check = check_arguments(catalog.behaviors["B"], {"X": 1})
    assert check.errors == ("B: X has a malformed specification in the catalog",)


@pytest.mark.parametrize(
    ("spec", "kind", "described"),
    [
        ("        allowed_values: [0.7, 5]", ArgumentKind.RANGE, "a number in [0.7, 5]"),
        ("        allowed_values: [-.inf, .inf]", ArgumentKind.RANGE, "a number in [-inf, inf]"),
        ("        allowed_values: [3, 3]", ArgumentKind.RANGE, "a number in [3, 3]"),
        ("        allowed_values: [up, Down]", ArgumentKind.SYMBOLS, "one of up, Down"),
        ("        allowed_values: TEXT", ArgumentKind.TEXT, "text"),
        # YAML 1.1 booleans stay words, as yaml-cpp's as<std::string>() reads them.
        ("        allowed_values: [ON, OFF]", ArgumentKind.SYMBOLS, "one of ON, OFF"),
        ("        allowed_values: [yes, no, true]", ArgumentKind.SYMBOLS, "one of yes, no, true"),
        (
            "        allowed_values: [-1, 1]\n        dimensions: 4",
            ArgumentKind.RANGE,
            "4 numbers in [-1, 1]",
        ),
    ],
)
def test_well_formed_argument_specs(spec: str, kind: ArgumentKind, described: str) -> None:
    catalog = parse_catalog(SPEC.replace("{spec}", spec))
    assert [d for d in catalog.diagnostics if d.severity is Severity.ERROR] == []
    (arg,) = catalog.behaviors["B"].arguments
    assert (arg.kind, arg.describe()) == (kind, described)


def test_argument_without_a_name() -> None:
    text = SPEC.replace("- argument: X", "- name: X").replace(
        "{spec}", "        allowed_values: TEXT"
    )
    catalog = parse_catalog(text)
    (error,) = [d for d in catalog.diagnostics if d.severity is Severity.ERROR]
    assert error.code == codes.MISSING_ERROR_TAG
    assert "an argument of B has no 'argument'" in error.message
    assert catalog.behaviors["B"].arguments == ()


# -- YAML-level problems ------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "needle", "message"),
    [
        ("behavior_descriptors: [\n", None, "invalid YAML"),
        ("a: b: c\n", ": c", "invalid YAML: mapping values are not allowed"),
        ("a: !!python/object/apply:os.system ['true']\n", "!!python", "is not allowed"),
        ("a: !!binary aGk=\n", "!!binary", "YAML tag 'tag:yaml.org,2002:binary' is not allowed"),
        ("a: 2001-12-14\n", "2001", "timestamp' is not allowed"),
        ("a: !!bool maybe\n", "!!bool", "bad scalar 'maybe': not a boolean"),
        ("a: !!int x\n", "!!int", "bad scalar 'x'"),
        ("a: &x [1, *x]\n", "*x", "recursive alias"),
        ("a: *nowhere\n", "*nowhere", "found undefined alias 'nowhere'"),
        ("a: &x 1\nb: &x 2\n", "&x 2", "found duplicate anchor 'x'"),
        ("base: &b {x: 1}\nc:\n  <<: *b\n", "<<", "merge keys"),
        ("? [a, b]\n: c\n", "[a, b]", "a mapping key must be a scalar"),
        ("a: 1\n---\nb: 2\n", "---", "expected a single document"),
        ("[1, 2]\n", "[1, 2]", "a catalog is a mapping with behavior_descriptors, got a list"),
        ("just text\n", "just", "got a str ('just text')"),
        ("", None, "empty document"),
        ("# only a comment\n", None, "empty document"),
    ],
)
def test_unreadable_yaml(text: str, needle: str | None, message: str) -> None:
    with pytest.raises(CatalogError) as err:
        parse_catalog(text, "y.yaml")
    assert message in err.value.message
    assert err.value.mark is not None and err.value.mark.file == "y.yaml"
    if needle is not None:
        assert at(err.value.mark) == where(text, needle)
    assert len(str(err.value).splitlines()) == 1


def test_python_tag_is_never_executed(tmp_path: Any) -> None:
    marker = tmp_path / "executed"
    text = f"a: !!python/object/apply:os.system ['touch {marker}']\n"
    with pytest.raises(CatalogError):
        parse_catalog(text)
    assert not marker.exists()


def test_alias_bomb_is_rejected_fast() -> None:
    lines = ['a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]']
    for prev, name in zip("abcdefgh", "bcdefghi", strict=True):
        lines.append(f"{name}: &{name} [" + ",".join([f"*{prev}"] * 9) + "]")
    text = "\n".join(lines) + "\n"
    start = time.perf_counter()
    with pytest.raises(CatalogError, match="too many nodes") as err:
        parse_catalog(text, "bomb.yaml")
    assert time.perf_counter() - start < 0.5
    # Reported where the expansion crosses the budget: an alias, not the first line.
    assert err.value.mark is not None
    line = text.splitlines()[err.value.mark.line - 1]
    assert line[err.value.mark.column - 1 : err.value.mark.column + 1] in {
        f"*{c}" for c in "abcdefgh"
    }


def test_aliases_within_budget_are_expanded() -> None:
    text = BASE.replace("incompatible_lists: [moves]", "incompatible_lists: &l [moves]")
    text = text.replace("behaviors: [GO]", "behaviors: *l")
    catalog = parse_catalog(text)
    assert catalog.lists["moves"].behaviors == ("moves",)


def test_budget_counts_every_alias_use() -> None:
    text = "x: &x [1, 2, 3, 4]\ny: [*x, *x, *x]\n"
    assert yamlnodes.load_yaml(text, "f", budget=100) is not None
    with pytest.raises(CatalogError, match="too many nodes"):
        yamlnodes.load_yaml(text, "f", budget=12)


@pytest.mark.parametrize(
    "text",
    [
        "a: " + "[" * 100_000 + "]" * 100_000 + "\n",  # PyYAML's C composer segfaults on this
        "a:\n" + "".join("  " * i + f"- k{i}:\n" for i in range(1, 400)),
    ],
)
def test_deep_nesting_is_an_error_not_a_crash(text: str) -> None:
    # Whichever stops the nesting first, PyYAML's parser (6.0.4 caps flow nesting itself)
    # or aeroexec's own depth check, the user gets one line at a place in the file: the
    # wording is the dependency's or ours, the behavior is aeroexec's.
    with pytest.raises(CatalogError) as err:
        parse_catalog(text, "deep.yaml")
    assert err.value.mark.file == "deep.yaml" and err.value.mark.line >= 1
    assert len(str(err.value).splitlines()) == 1


def test_nesting_beyond_aeroexecs_own_bound_is_refused_with_its_depth() -> None:
    # 201 levels in block style: far below any YAML parser's own cap, so this is our check.
    text = "a:\n" + "".join("  " * i + f"- k{i}:\n" for i in range(1, yamlnodes.MAX_DEPTH + 2))
    with pytest.raises(CatalogError, match=f"nested more than {yamlnodes.MAX_DEPTH} levels"):
        parse_catalog(text, "deep.yaml")


def test_utf8_bom_is_accepted() -> None:
    assert "GO" in parse_catalog("\ufeff" + BASE).behaviors


def test_names_with_line_breaks_stay_on_one_line() -> None:
    # Found by the fuzzer: a key with a newline split a diagnostic line in two.
    text = '"bad\\nkey": 1\n"B\\u2028X": 2\nbehavior_descriptors: []\ncapability_descriptors: []\n'
    catalog = parse_catalog(text, "c.yaml")
    unknown = [str(d) for d in only(catalog, codes.UNKNOWN_TAG)]
    assert unknown == [
        "c.yaml:1:1: warning AX104 unknown tag 'bad\\nkey' in the catalog",
        "c.yaml:2:1: warning AX104 unknown tag 'B\\u2028X' in the catalog",
    ]
    assert only(catalog, codes.UNKNOWN_TAG)[0].message == "unknown tag 'bad\nkey' in the catalog"
    with pytest.raises(CatalogError) as err:
        parse_catalog('"a\\rb": !!python/none x\n', "c.yaml")
    assert "\r" not in str(err.value) and len(str(err.value).splitlines()) == 1
