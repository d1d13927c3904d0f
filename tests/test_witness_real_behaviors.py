"""Witnesses completed for the real behaviors: the setup that makes a step's situation
hold (TAKE_OFF before a motion behavior), arguments that keep a behavior running, and an
honest caveat when the real behaviors cannot reproduce the witness."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.behaviors import STANDARD_LIBRARY
from aeroexec.catalog import read_catalog
from aeroexec.catalog.loader import parse_catalog
from aeroexec.cli import app
from aeroexec.verifier import Outcome, Step, Witness, check_catalog
from aeroexec.verifier.witness_run import (
    WitnessMismatch,
    argument_choices,
    explains,
    model_reason,
    realize,
    run,
)

REAL = Path(__file__).resolve().parent / "fixtures" / "verifier_catalogs"
JACEK = REAL / "JacekCieslak95+behavior_take_off2__behavior_catalog__8bbe12d.yaml"

#: GO_TO_POINT preempts ROTATE but not the other way round (an AX401 finding): the witness
#: "GO_TO_POINT, then ROTATE: both stay active" needs the drone flying and arguments.
ONE_SIDED = """\
behavior_descriptors:
  - behavior: TAKE_OFF
    timeout: 15
    recurrent: no
  - behavior: GO_TO_POINT
    timeout: 60
    recurrent: no
    incompatible_lists: [rotation]
    capabilities: [FLIGHT]
    arguments:
      - argument: coordinates
        allowed_values: [-100, 100]
        dimensions: 3
      - argument: relative_coordinates
        allowed_values: [-100, 100]
        dimensions: 3
  - behavior: ROTATE
    timeout: 15
    recurrent: no
    capabilities: [FLIGHT]
    arguments:
      - argument: angle
        allowed_values: [-360, 360]
behavior_lists:
  - list: rotation
    behaviors: [ROTATE]
capability_descriptors:
  - capability: FLIGHT
    active_by_default: no
    processes: [controller]
"""


def test_a_motion_witness_gets_a_take_off_first_and_fails_without_it() -> None:
    catalog = read_catalog(JACEK)
    finding = next(f for f in check_catalog(catalog) if f.rule == "AX304" and f.witness)
    assert finding.witness is not None
    original = finding.witness
    assert original.setup == ()
    with pytest.raises(WitnessMismatch, match="situation: FOLLOW_OBJECT_IMAGE: not flying"):
        run(catalog, original, STANDARD_LIBRARY)
    realized = realize(catalog, original, STANDARD_LIBRARY)
    assert realized.setup == (Step("TAKE_OFF"),)
    assert realized.steps == original.steps and not realized.caveat
    done = run(catalog, realized, STANDARD_LIBRARY)
    assert explains(model_reason(catalog, original), done.error)
    assert "conflicts with active capability" in done.error
    assert done.executive.vehicle.state().flying
    assert realized.describe().startswith("run TAKE_OFF to its end, then activate ")
    assert realized.to_list()[0] == {"activate": "TAKE_OFF", "arguments": {}, "until_end": True}


def test_steps_get_arguments_that_keep_the_real_behaviors_running() -> None:
    catalog = parse_catalog(ONE_SIDED, "one_sided.yaml")
    finding = next(f for f in check_catalog(catalog) if f.rule == "AX401")
    assert finding.witness is not None and finding.witness.outcome is Outcome.ALL_ACTIVE
    assert [s.activate for s in finding.witness.steps] == ["GO_TO_POINT", "ROTATE"]
    realized = realize(catalog, finding.witness, STANDARD_LIBRARY)
    assert not realized.caveat, realized.caveat
    assert realized.setup == (Step("TAKE_OFF"),)
    # No arguments: GO_TO_POINT fails in on_start; both: it refuses; one works.
    assert realized.steps == (
        Step("GO_TO_POINT", (("coordinates", [0, 0, 0]),)),
        Step("ROTATE", (("angle", 0),)),
    )
    executive = run(catalog, realized, STANDARD_LIBRARY).executive
    assert executive.active_behaviors == ("GO_TO_POINT", "ROTATE")
    with pytest.raises(WitnessMismatch, match="step GO_TO_POINT ended at once: PROCESS_FAILURE"):
        run(
            catalog,
            Witness(finding.witness.steps, Outcome.ALL_ACTIVE, realized.setup),
            STANDARD_LIBRARY,
        )


def test_argument_choices_follow_the_catalog_and_the_declared_names() -> None:
    catalog = parse_catalog(ONE_SIDED, "one_sided.yaml")
    go_to = catalog.behaviors["GO_TO_POINT"]
    assert [
        dict(s.arguments) for s in argument_choices(go_to, STANDARD_LIBRARY["GO_TO_POINT"])
    ] == [
        {},
        {"coordinates": [0, 0, 0], "relative_coordinates": [0, 0, 0]},
        {"coordinates": [0, 0, 0]},
        {"relative_coordinates": [0, 0, 0]},
    ]
    # An implementation that declares it reads nothing gets no arguments to try.
    assert [s.arguments for s in argument_choices(go_to, STANDARD_LIBRARY["TAKE_OFF"])] == [()]


def test_a_witness_the_real_behaviors_cannot_reproduce_says_so() -> None:
    catalog = parse_catalog(ONE_SIDED, "one_sided.yaml")
    # TAKE_OFF after GO_TO_POINT needs the drone on the ground and flying at once.
    impossible = Witness((Step("GO_TO_POINT"), Step("TAKE_OFF")), Outcome.ALL_ACTIVE)
    realized = realize(catalog, impossible, STANDARD_LIBRARY)
    assert realized.caveat.startswith("not reproduced with the real behaviors: situation: ")
    assert realized.steps == impossible.steps and realized.setup == ()
    assert realized.describe().endswith(f"stay active ({realized.caveat})")


def test_a_rejection_for_another_reason_is_not_the_witness() -> None:
    catalog = parse_catalog(ONE_SIDED, "one_sided.yaml")
    # ROTATE is not rejected on capabilities here; a situation refusal is not the reason.
    witness = Witness((Step("ROTATE"),), Outcome.REJECTED)
    with pytest.raises(WitnessMismatch, match="situation: ROTATE: not flying"):
        run(catalog, witness, STANDARD_LIBRARY, reason="conflict with referenced")
    assert not explains("conflict with referenced", "ROTATE: not flying")
    assert explains("unknown behavior", "unknown behavior FOO (did you mean 'FLIP'?)")


def test_verify_completes_witnesses_only_for_a_project_with_behaviors(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "pyproject.toml").write_text('[project]\nname = "x"\n')
    plain = CliRunner().invoke(app, ["verify", str(JACEK), "--witness", "--format", "json"])
    assert "until_end" not in plain.stdout
    (tmp_path / "aeroexec.toml").write_text(f'behaviors = []\ncatalog = "{JACEK}"\n')
    result = CliRunner().invoke(app, ["verify", "--witness"])
    assert result.exit_code == 1
    assert "witness: run TAKE_OFF to its end, then activate GO_TO_POINT_ANGLE" in result.stdout
    # ... and checks the catalog against the code: these behaviors have none here.
    assert "error AX901 GO_TO_POINT_ANGLE has no implementation (looked in: " in result.stdout
    assert "AX901" not in plain.stdout
