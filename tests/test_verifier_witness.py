"""Witnesses replay in the real executive core, with the real behaviors, and make the
problem happen for the reason the verifier gives.

Every finding with a witness (from the rule fixtures, from the real catalogs and from
generated catalogs) is replayed step by step against `aeroexec.executive.Executive`
with the standard library (stand-ins, explicitly, for behaviors it does not implement):
the outcome the verifier predicts is the outcome the executive produces, and a rejection
says the model's reason. Near-miss catalogs show the same steps succeeding once the
defect is repaired.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from aeroexec.behaviors import STANDARD_LIBRARY
from aeroexec.catalog import read_catalog
from aeroexec.catalog.loader import parse_catalog
from aeroexec.catalog.model import Catalog
from aeroexec.errors import CatalogError
from aeroexec.executive import Executive, GenericBehavior, Library
from aeroexec.verifier import Finding, Outcome, Witness, check_catalog
from aeroexec.verifier.witness_run import explains, model_reason, realize, run

FIXTURES = Path(__file__).resolve().parent / "fixtures"
RULES = FIXTURES / "verifier" / "rules"
REAL = FIXTURES / "verifier_catalogs"


def replay(catalog: Catalog, witness: Witness, library: Library = STANDARD_LIBRARY) -> Executive:
    """Run the witness with the real behaviors; assert the executive does what the
    witness says, for the reason the model gives.

    The witness is first completed for the behaviors (`realize`: TAKE_OFF before a motion
    behavior, arguments the catalog accepts); catalog behaviors the library does not
    implement run as explicit stand-ins. Initiation may fail for another finding of the
    same catalog; the model knows that no default capability is then referenced, and so
    does the executive.
    """
    realized = realize(catalog, witness, library)
    assert not realized.caveat, realized.describe()
    assert realized.outcome is witness.outcome
    assert [s.activate for s in realized.steps] == [s.activate for s in witness.steps]
    done = run(catalog, realized, library)
    executive = done.executive
    if witness.outcome is Outcome.INITIATION_FAILS:
        assert not executive.initiation.ok and executive.initiation.error
    elif witness.outcome is Outcome.REJECTED:
        reason = model_reason(catalog, witness)
        assert reason and explains(reason, done.error), (reason, done.error)
        assert realized.steps[-1].activate not in executive.active_behaviors
    else:
        for step in realized.steps:
            assert step.activate in executive.active_behaviors
    return executive


def witnessed(findings: list[Finding]) -> list[Finding]:
    return [f for f in findings if f.witness is not None]


FIXTURE_CATALOGS = sorted(p for p in RULES.glob("AX*.yaml") if ".clean" not in p.name)
WITNESSED = [
    (path, finding)
    for path in FIXTURE_CATALOGS
    for finding in witnessed(check_catalog(read_catalog(path)))
]


def test_every_witness_rule_has_a_witnessed_fixture_finding() -> None:
    from aeroexec.verifier import all_rules

    with_witness = {r.code for r in all_rules() if r.witness and r.kind == "catalog"}
    assert with_witness == {"AX203", "AX205", "AX301", "AX302", "AX303", "AX304", "AX401", "AX502"}
    assert {f.rule for _, f in WITNESSED} == with_witness


@pytest.mark.parametrize(
    ("path", "finding"),
    WITNESSED,
    ids=[f"{p.stem}:{f.line}" for p, f in WITNESSED],
)
def test_fixture_witness_replays_in_the_executive(path: Path, finding: Finding) -> None:
    assert finding.witness is not None
    replay(read_catalog(path), finding.witness)


def test_witnesses_are_shortest() -> None:
    by_rule: dict[str, set[int]] = {}
    for _, finding in WITNESSED:
        assert finding.witness is not None
        by_rule.setdefault(finding.rule, set()).add(len(finding.witness.steps))
    assert by_rule["AX302"] == {0}
    for code in ("AX203", "AX205", "AX301", "AX303", "AX502"):
        assert by_rule[code] == {1}, code
    assert by_rule["AX304"] == {2}
    assert by_rule["AX401"] == {2}


def test_witness_json_shape() -> None:
    finding = next(f for _, f in WITNESSED if f.rule == "AX304")
    assert finding.to_dict()["witness"] == [
        {"activate": "GO_TO", "arguments": {}},
        {"activate": "FOLLOW", "arguments": {}},
    ]


def test_repaired_catalog_accepts_the_same_steps() -> None:
    """The AX304 witness against its clean near-miss: FOLLOW preempts GO_TO cleanly."""
    executive = Executive(
        read_catalog(RULES / "AX304.clean.yaml"), library={}, stand_in=GenericBehavior
    )
    assert executive.activate_behavior("GO_TO").ok
    assert executive.activate_behavior("FOLLOW").ok
    assert executive.active_behaviors == ("FOLLOW",)


def test_repaired_defaults_initiate() -> None:
    assert Executive(
        read_catalog(RULES / "AX302.clean.yaml"), library={}, stand_in=GenericBehavior
    ).initiation.ok


def test_asymmetric_witness_order_matters() -> None:
    """AX401's witness leaves both running; the opposite order preempts."""
    catalog = read_catalog(RULES / "AX401.yaml")
    executive = Executive(catalog, library={}, stand_in=GenericBehavior)
    assert executive.activate_behavior("GO_TO").ok
    assert executive.activate_behavior("DOCK").ok
    assert "GO_TO" not in executive.active_behaviors


def _readable(path: Path) -> bool:
    try:
        read_catalog(path)
    except CatalogError:
        return False  # the task-based formats, refused by the loader
    return True


READABLE_REAL = [p for p in sorted(REAL.glob("*.yaml")) if _readable(p)]


def test_real_catalogs_with_witnesses_are_covered() -> None:
    assert len(READABLE_REAL) == 12
    assert sum(bool(witnessed(check_catalog(read_catalog(p)))) for p in READABLE_REAL) >= 6


@pytest.mark.parametrize("path", READABLE_REAL, ids=lambda p: p.name[:60])
def test_real_catalog_witnesses_replay(path: Path) -> None:
    catalog = read_catalog(path)
    for finding in witnessed(check_catalog(catalog)):
        assert finding.witness is not None
        replay(catalog, finding.witness)


# -- generated catalogs: the verifier's model and the executive agree ---------------------
NAMES = [f"B{i}" for i in range(6)]
LISTS = [f"l{i}" for i in range(3)]
CAPS = [f"C{i}" for i in range(5)]


@st.composite
def small_catalogs(draw: st.DrawFn) -> str:
    """Thesis-dialect catalogs with generic behavior names (so the executive uses its
    generic behavior), random lists, capabilities, conflicts, requirements, defaults
    and a few dangling references."""
    behaviors = draw(st.lists(st.sampled_from(NAMES), min_size=1, max_size=6, unique=True))
    lines = ["behavior_descriptors:"]
    for name in behaviors:
        lists = draw(st.lists(st.sampled_from([*LISTS, "lx"]), max_size=2, unique=True))
        caps = draw(st.lists(st.sampled_from([*CAPS, "CX"]), max_size=3, unique=True))
        recurrent = draw(st.booleans())
        lines += [
            f"  - behavior: {name}",
            "    timeout: 10",
            f"    recurrent: {'yes' if recurrent else 'no'}",
            f"    incompatible_lists: [{', '.join(lists)}]",
            f"    capabilities: [{', '.join(caps)}]",
        ]
    lines.append("behavior_lists:")
    for list_name in LISTS:
        members = draw(st.lists(st.sampled_from([*NAMES, "BX"]), max_size=4, unique=True))
        lines += [f"  - list: {list_name}", f"    behaviors: [{', '.join(members)}]"]
    lines.append("capability_descriptors:")
    for cap in CAPS:
        others = [c for c in CAPS if c != cap]
        conflicts = draw(st.lists(st.sampled_from(others), max_size=2, unique=True))
        required = draw(st.lists(st.sampled_from([*others, "CY"]), max_size=1, unique=True))
        default = draw(st.integers(0, 9)) == 0
        lines += [
            f"  - capability: {cap}",
            f"    active_by_default: {'yes' if default else 'no'}",
            f"    processes: [p_{cap.lower()}]",
            f"    incompatible_capabilities: [{', '.join(conflicts)}]",
            f"    required_capabilities: [{', '.join(required)}]",
        ]
    return "\n".join(lines) + "\n"


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(small_catalogs())
def test_generated_catalog_witnesses_replay(text: str) -> None:
    catalog = parse_catalog(text, "generated.yaml")
    for finding in witnessed(check_catalog(catalog)):
        assert finding.witness is not None
        replay(catalog, finding.witness, library={})  # every behavior a stand-in
