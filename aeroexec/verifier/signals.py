"""Property files against a catalog (AX75x): the behaviors, capabilities and faults a
formula names must exist, or the property watches a signal that is 0 in every flight.

The verifier does not parse property files (that is `aeroexec.properties`, a tool beside
it): it is given each use of a per-name signal — `active_GO_TO_POINT`, `command_LAND`,
`capability_SELF_LOCALIZATION_BY_ODOMETRY`, `fault_low_battery` — with its place, and
judges the names against each behavior catalog.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from aeroexec.catalog.model import Catalog, Severity
from aeroexec.errors import Mark
from aeroexec.verifier.findings import Finding
from aeroexec.verifier.registry import property_rule
from aeroexec.verifier.suggest import Suggester

#: The faults a recording can show (docs/properties.md#signals).
FAULT_KINDS = (
    "battery_empty",
    "link_lost",
    "low_battery",
    "mode_changed",
    "not_connected",
    "position_lost",
    "stuck_motor",
)

UNKNOWN_BEHAVIOR = property_rule(
    "AX751",
    "property-unknown-behavior",
    Severity.ERROR,
    """A property names a behavior the catalog does not define (`active_B`, `command_B`).
    In flight the signal is 0 throughout, so the property holds or fails for the wrong
    reason: `always((active_GO_TO_PIONT >= 1) implies ...)` never checks anything, and a
    geofence meant for one behavior guards nothing. Fix the name (behaviors are spelled as
    in the catalog) or remove the property.""",
)
UNKNOWN_CAPABILITY = property_rule(
    "AX752",
    "property-unknown-capability",
    Severity.ERROR,
    """A property names a capability the catalog does not define (`capability_C`). In
    flight the signal is 0 throughout, so the property checks nothing about it. Fix the
    name as the catalog spells it.""",
)
UNKNOWN_FAULT = property_rule(
    "AX753",
    "property-unknown-fault",
    Severity.WARNING,
    """A property names a fault no vehicle reports (`fault_K`; the kinds are
    battery_empty, link_lost, low_battery, mode_changed, not_connected, position_lost,
    stuck_motor). In flight the signal is 0 throughout: a reaction to that fault is never
    checked. A vehicle backend with faults of its own may report others. Fix the name
    otherwise.""",
)


@dataclass(frozen=True, slots=True)
class SignalUse:
    """One use of a signal in a property file: its name and where it is written."""

    name: str
    mark: Mark


def check_signal_uses(
    uses: Iterable[SignalUse], catalog: Catalog, note: str = "", *, faults: bool = True
) -> list[Finding]:
    """Findings for the names `uses` give that `catalog` lacks; `faults`: also the fault
    kinds (which do not depend on the catalog: judged once however many catalogs)."""
    findings = []
    for use in uses:
        name = use.name
        if name.startswith(("active_", "command_")):
            behavior = name.split("_", 1)[1]
            if behavior not in catalog.behaviors:
                hint = Suggester(catalog.behaviors).hint(behavior)
                findings.append(
                    Finding.at(
                        UNKNOWN_BEHAVIOR.code,
                        Severity.ERROR,
                        f"{name}: no behavior {behavior} in the catalog{hint}{note}",
                        use.mark,
                        (behavior,),
                    )
                )
        elif name.startswith("capability_"):
            capability = name.removeprefix("capability_")
            if capability not in catalog.capabilities:
                hint = Suggester(catalog.capabilities).hint(capability)
                findings.append(
                    Finding.at(
                        UNKNOWN_CAPABILITY.code,
                        Severity.ERROR,
                        f"{name}: no capability {capability} in the catalog{hint}{note}",
                        use.mark,
                        (capability,),
                    )
                )
        elif faults and name.startswith("fault_"):
            kind = name.removeprefix("fault_")
            if kind not in FAULT_KINDS:
                hint = Suggester(FAULT_KINDS).hint(kind)
                findings.append(
                    Finding.at(
                        UNKNOWN_FAULT.code,
                        Severity.WARNING,
                        f"{name}: no vehicle reports a fault {kind}{hint}",
                        use.mark,
                        (kind,),
                    )
                )
    return findings
