"""The loader, the verifier and the executive agree on what a catalog means.

Each case was found as a disagreement: `verify` passed a catalog that `run` then
crashed on, or a message claimed something the activation model contradicts.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.catalog import parse_catalog
from aeroexec.cli import app
from aeroexec.executive import Executive, GenericBehavior
from aeroexec.verifier import check_catalog

ROOT = Path(__file__).resolve().parent.parent
MISSION = ROOT / "missions" / "appendix_c.py"
runner = CliRunner()

CATALOG = """\
behavior_descriptors:
  - behavior: TAKE_OFF
    timeout: {timeout}
    recurrent: no
capability_descriptors: []
"""


@pytest.mark.parametrize("timeout", [".inf", "1.0e+300"])
def test_a_timeout_the_clock_cannot_arm_fails_verify_and_run_alike(
    tmp_path: Path, timeout: str
) -> None:
    catalog = tmp_path / "catalog.yaml"
    catalog.write_text(CATALOG.format(timeout=timeout), encoding="utf-8")
    where = f"{catalog}:3:14"
    verified = runner.invoke(app, ["verify", str(catalog)])
    assert verified.exit_code == 1
    assert f"{where}: error AX105 TAKE_OFF: timeout must be at most" in verified.stdout
    ran = runner.invoke(app, ["run", str(MISSION), "-c", str(catalog)])
    assert ran.exit_code == 2
    assert "Traceback" not in ran.stderr and "OverflowError" not in ran.output
    [line] = ran.stderr.strip().splitlines()
    assert line.startswith(f"{where}: error: TAKE_OFF: timeout must be at most")


ONE_SIDED = textwrap.dedent(
    """\
    behavior_descriptors:
      - behavior: GO
        timeout: 10
        recurrent: no
        incompatible_lists: [moves]
        capabilities: [FLIGHT_CONTROL]
      - behavior: FOLLOW
        timeout: 10
        recurrent: no
        capabilities: [{follow_capability}]
    behavior_lists:
      - list: moves
        behaviors: [FOLLOW]
    capability_descriptors:
      - capability: FLIGHT_CONTROL
        active_by_default: no
        processes: [controller]
        incompatible_capabilities: [SERVOING]
      - capability: SERVOING
        active_by_default: no
        processes: [servo]
    """
)


def test_one_sided_preemption_claims_coexistence_only_when_the_executive_allows_it() -> None:
    conflicting = parse_catalog(ONE_SIDED.format(follow_capability="SERVOING"))
    [finding] = [f for f in check_catalog(conflicting) if f.rule == "AX401"]
    assert "runs beside it" not in finding.message
    assert "never run together" in finding.message
    assert "FOLLOW is rejected (its capabilities conflict with GO's)" in finding.message
    executive = Executive(conflicting, library={}, stand_in=GenericBehavior)
    assert executive.activate_behavior("GO").ok
    assert not executive.activate_behavior("FOLLOW").ok

    free = parse_catalog(ONE_SIDED.format(follow_capability="FLIGHT_CONTROL"))
    [finding] = [f for f in check_catalog(free) if f.rule == "AX401"]
    assert finding.message.endswith("activated after GO, FOLLOW runs beside it")
    executive = Executive(free, library={}, stand_in=GenericBehavior)
    assert executive.activate_behavior("GO").ok and executive.activate_behavior("FOLLOW").ok
    assert executive.active_behaviors == ("GO", "FOLLOW")
