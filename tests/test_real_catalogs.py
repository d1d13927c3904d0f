"""Every real Aerostack catalog in tests/fixtures/catalogs/real either loads or is refused
with a precise message. Provenance of each file: tests/fixtures/catalogs/README.md.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import pytest
import yaml

from aeroexec.catalog import Severity, check_arguments, load_catalog, read_catalog, yamlnodes
from aeroexec.catalog.show import catalog_to_json, render_plain
from aeroexec.errors import CatalogError

REAL = Path(__file__).resolve().parent / "fixtures" / "catalogs" / "real"
QC = "Ahrovan+quadrotor_stack_configs__"
TASK_FORMAT = "Aerostack 4.x task-based catalog"


@dataclass(frozen=True)
class Loads:
    behaviors: int  # distinct names (the later duplicate wins)
    lists: int
    capabilities: int
    definitions: int | None = None  # behavior definitions incl. duplicates, when different
    warnings: tuple[str, ...] = ()  # codes of warning diagnostics, in file order
    strict_error: str | None = None  # load_catalog refuses it with this message
    dialect: str = "aerostack-2.x"


@dataclass(frozen=True)
class Refused:
    message: str
    line: int
    column: int


EXPECTED: dict[str, Loads | Refused] = {
    # IMAV 2017 catalogs: dangling list members and an undefined incompatible capability,
    # but nothing a loader must stop on (the verifier reports them).
    f"{QC}drone1_catalog_imav__ead04dd.yaml": Loads(7, 2, 8),
    f"{QC}drone1_catalog_imav__0281478.yaml": Loads(7, 2, 4),
    # SELF_LOCALIZE_BY_ODOMETRY without category: the default block makes it goal-based.
    f"{QC}drone2_catalog_imav_mission2__0b01192.yaml": Loads(7, 2, 9),
    # TAB after a value: valid YAML (libyaml agrees); see test_tab_after_value below.
    f"{QC}drone3_catalog_imav_mission3__4f0929d.yaml": Loads(5, 1, 2),
    f"{QC}drone4_catalog_imav__cad9aae.yaml": Loads(7, 2, 8),
    # capability_descriptors is commented out: an error tag (thesis 3.3.1) is missing.
    f"{QC}drone5_catalog_imav__0281478.yaml": Loads(
        2, 1, 0, strict_error="1:1: error: missing 'capability_descriptors'"
    ),
    # LAND_ON_STATIC_PLATFORM is defined twice (lines 72 and 93): duplicate warning.
    f"{QC}drone1_behavior_catalog__0349293.yaml": Loads(17, 2, 10, 18, ("AX106",)),
    # The Aerostack 2.0 default catalog and its two November 2017 revisions.
    f"{QC}drone1_behavior_catalog__451fc45.yaml": Loads(11, 2, 8),
    f"{QC}drone1_behavior_catalog__e3eac89.yaml": Loads(11, 2, 8),
    f"{QC}drone1_behavior_catalog__85c888c.yaml": Loads(11, 2, 8),
    # Last 2.x version: one more behavior (RECOGNIZE_QR) and capability (QR_RECOGNITION).
    f"{QC}drone1_behavior_catalog__cd745c9.yaml": Loads(12, 2, 9),
    # A user's own catalog: float bounds, otherwise the 2.0 default's structure.
    "JacekCieslak95+behavior_take_off2__behavior_catalog__8bbe12d.yaml": Loads(14, 2, 8),
    # 2020-2021 task format (behaviors -> tasks, default_values, exclusivity_constraints):
    # a different executive; refused by name at the document's first key (after the
    # 47-line comment header every one of them carries).
    "cvar-upm+aerostack__config_mission_behavior_catalog__abbd8b2.yaml": Refused(
        TASK_FORMAT, 48, 1
    ),
    "aerostack-lab+basic_mission_bebop__configs_mission_behavior_catalog__9083d30.yaml": Refused(
        TASK_FORMAT, 48, 1
    ),
    "aerostack+basic_mission_pixhawk_gazebo__configs_mission_behavior_catalog__488ed5c.yaml": (
        Refused(TASK_FORMAT, 48, 1)
    ),
    "aerostack-lab+behavior_tree_tello__configs_mission_behavior_catalog__a406a68.yaml": Refused(
        TASK_FORMAT, 48, 1
    ),
    "cvar-upm+coordinator_cbc__behavior_coordinator_src_test_behavior_catalog__4edaaf8.yaml": (
        Refused(TASK_FORMAT, 48, 1)
    ),
    "cvar-upm+coordinator_cbc__behavior_coordinator_src_test_bad_behavior_catalog__4edaaf8.yaml": (
        Refused(TASK_FORMAT, 48, 1)
    ),
    (
        "cvar-upm+coordinator_cbc__behavior_coordinator_src_test_"
        "behavior_catalog_impossible__4edaaf8.yaml"
    ): Refused(TASK_FORMAT, 48, 1),
    (
        "cvar-upm+coordinator_cbc__behavior_coordinator_src_test_"
        "behavior_catalog_missing_task__4edaaf8.yaml"
    ): Refused(TASK_FORMAT, 48, 1),
}


def test_every_fixture_has_an_expectation() -> None:
    assert sorted(p.name for p in REAL.glob("*.yaml")) == sorted(EXPECTED)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_real_catalog(name: str) -> None:
    path = REAL / name
    expected = EXPECTED[name]
    if isinstance(expected, Refused):
        with pytest.raises(CatalogError) as err:
            read_catalog(path)
        assert expected.message in err.value.message
        assert "2020-2021" in err.value.message  # says which format it is, and when
        assert err.value.mark is not None
        assert (err.value.mark.file, err.value.mark.line, err.value.mark.column) == (
            str(path),
            expected.line,
            expected.column,
        )
        return
    catalog = read_catalog(path)
    assert (len(catalog.behaviors), len(catalog.lists), len(catalog.capabilities)) == (
        expected.behaviors,
        expected.lists,
        expected.capabilities,
    )
    assert len(catalog.all_behaviors) == (expected.definitions or expected.behaviors)
    assert catalog.dialect == expected.dialect
    warnings = tuple(d.code for d in catalog.diagnostics if d.severity is Severity.WARNING)
    assert warnings == expected.warnings
    if expected.strict_error is None:
        assert load_catalog(path).behaviors == catalog.behaviors
    else:
        with pytest.raises(CatalogError) as err:
            load_catalog(path)
        assert str(err.value).startswith(f"{path}:{expected.strict_error}")


def _real(name: str) -> Path:
    return REAL / name


def test_imav_recognize_qr_timeout() -> None:
    catalog = read_catalog(_real(f"{QC}drone1_catalog_imav__0281478.yaml"))
    qr = catalog.behaviors["RECOGNIZE_QR"]
    assert (qr.timeout, qr.recurrent, qr.capabilities) == (5.0, False, ("QR_RECOGNITION",))


def test_odometry_without_category_is_goal_based() -> None:
    # NOTES.md section 2: a localization behavior that would time out after 15 s.
    for name in (
        f"{QC}drone2_catalog_imav_mission2__0b01192.yaml",
        f"{QC}drone4_catalog_imav__cad9aae.yaml",
    ):
        odometry = read_catalog(_real(name)).behaviors["SELF_LOCALIZE_BY_ODOMETRY"]
        assert (odometry.recurrent, odometry.timeout) == (False, 15.0), name


def test_duplicate_behavior_in_0349293() -> None:
    path = _real(f"{QC}drone1_behavior_catalog__0349293.yaml")
    catalog = read_catalog(path)
    (dup,) = [d for d in catalog.diagnostics if d.code == "AX106"]
    assert (dup.mark.line, dup.mark.column) == (93, 5)
    assert "LAND_ON_STATIC_PLATFORM" in dup.message and "first at line 72" in dup.message
    definitions = [b for b in catalog.all_behaviors if b.name == "LAND_ON_STATIC_PLATFORM"]
    assert [b.mark.line for b in definitions] == [72, 93]
    assert catalog.behaviors["LAND_ON_STATIC_PLATFORM"] is definitions[1]  # the later one wins
    (ignored,) = [d for d in catalog.diagnostics if d.code == "AX110"]
    assert ignored.mark.line == 121  # reactive_activation


def test_misspelt_list_does_not_stop_loading() -> None:
    # Every 2.x catalog names `self_localizaion_behaviors` (sic); the executive must
    # still load it: the undefined list just preempts nothing.
    catalog = read_catalog(_real(f"{QC}drone1_behavior_catalog__451fc45.yaml"))
    marker = catalog.behaviors["SELF_LOCALIZE_BY_VISUAL_MARKER"]
    assert marker.incompatible_lists == ("self_localizaion_behaviors",)
    assert "self_localizaion_behaviors" not in catalog.lists
    assert catalog.preempted_by("SELF_LOCALIZE_BY_VISUAL_MARKER") == frozenset()
    assert marker.mark_of("incompatible_lists.0").line == 70


def test_argument_names_across_revisions() -> None:
    old = read_catalog(_real(f"{QC}drone1_behavior_catalog__451fc45.yaml"))
    new = read_catalog(_real(f"{QC}drone1_behavior_catalog__85c888c.yaml"))
    assert [a.name for a in old.behaviors["GO_TO_POINT"].arguments] == [
        "POSITION",
        "RELATIVE_COORDINATES",
    ]
    assert [a.name for a in new.behaviors["GO_TO_POINT"].arguments] == [
        "coordinates",
        "relative_coordinates",
    ]
    # The Appendix C mission's call is valid for the lower-cased catalog only.
    call = {"coordinates": [3, 5.5, 1.3]}
    assert check_arguments(new.behaviors["GO_TO_POINT"], call).values == {
        "coordinates": [3, 5.5, 1.3]
    }
    assert not check_arguments(old.behaviors["GO_TO_POINT"], call).ok


def test_float_bounds_of_a_user_catalog() -> None:
    catalog = read_catalog(
        _real("JacekCieslak95+behavior_take_off2__behavior_catalog__8bbe12d.yaml")
    )
    (altitude,) = catalog.behaviors["TAKE_OFF2"].arguments
    assert (altitude.name, altitude.minimum, altitude.maximum) == ("ALTITUDE", 0.7, 5.0)
    assert check_arguments(catalog.behaviors["TAKE_OFF2"], {"altitude": 0.7}).ok
    assert not check_arguments(catalog.behaviors["TAKE_OFF2"], {"altitude": 0.6}).ok


def test_dangling_required_capability_is_kept() -> None:
    catalog = read_catalog(_real(f"{QC}drone1_behavior_catalog__e3eac89.yaml"))
    obstacle = catalog.capabilities["OBSTACLE_DETECTION_BY_VISUAL_MARKERS"]
    assert obstacle.required_capabilities == ("SELF_LOCALIZATION_BY_VISUAL_MARKERS",)
    assert "SELF_LOCALIZATION_BY_VISUAL_MARKERS" not in catalog.capabilities


def test_tab_after_value(monkeypatch: pytest.MonkeyPatch) -> None:
    """YAML allows a TAB as separation space; libyaml accepts it, PyYAML's pure-Python
    scanner does not (its known bug). Which one runs depends on how PyYAML was built, so
    the same flown catalog loads on one machine and not on another."""
    path = _real(f"{QC}drone3_catalog_imav_mission3__4f0929d.yaml")
    assert path.read_text(encoding="utf-8").splitlines()[10] == "    timeout: 20\t"
    if yamlnodes.HAS_C_LOADER:
        assert read_catalog(path).behaviors["LAND"].timeout == 20.0
    monkeypatch.setattr(yamlnodes, "_Loader", yaml.SafeLoader)
    with pytest.raises(CatalogError) as err:
        read_catalog(path)
    assert str(err.value) == (
        f"{path}:11:16: error: invalid YAML: found character '\\t' that cannot start any token"
    )


@pytest.mark.parametrize(
    "name", sorted(n for n, e in EXPECTED.items() if isinstance(e, Loads) and not e.strict_error)
)
def test_real_catalog_renders(name: str) -> None:
    catalog = load_catalog(REAL / name)
    text = render_plain(catalog)
    for behavior in catalog.behaviors:
        assert f"\n  {behavior}  timeout " in text
    data = json.loads(json.dumps(catalog_to_json(catalog), allow_nan=False))
    assert [b["name"] for b in data["behaviors"]] == list(catalog.behaviors)
