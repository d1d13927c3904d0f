"""Where each part of a session goes in Rerun's entity tree.

One `Layout` per recording: a single recording sits at the top of the tree (root ""),
two recordings shown side by side sit under `/base` and `/new`. Converter, blueprint and
tests all take their paths from here, so the tree is described in one place:

    {root}/world/markers          Points3D (static), labeled visual markers of world.yaml
    {root}/world/object           Points3D, the object to follow, where it is at each state
    {root}/vehicle                Transform3D (pose) + axes; {root}/vehicle/body a Boxes3D
    {root}/trajectory             Points3D, one point per vehicle/state message
    {root}/trajectory/line        LineStrips3D, one segment per vehicle/state message
    {root}/telemetry/<name>       Scalars: battery (%), altitude (m), speed (m/s)
    {root}/behaviors/active/<B>   Scalars: 1 while behavior B is active, 0 otherwise
    {root}/behaviors/state/<B>    StateChange: "#uid args" while active, reset when it ends
    {root}/capabilities/<C>       Scalars: reference count of capability C
    {root}/processes/<P>          StateChange: process P's state, reset when stopped
    {root}/properties/<P>         StateChange: "violated" over property P's first violating
                                  interval (run/fly --spec, docs/properties.md)
    {root}/events                 TextLog: one row per behavior_event
    {root}/errors                 TextLog: rejected activations, failed calls, vehicle faults,
                                  violated properties
    {root}/calls                  TextLog: the service call tree, indented by depth
    {root}/mission                TextLog: mission/command (what the mission asked)
    {root}/log                    TextLog: the session's foxglove.Log messages
    {root}/beliefs                TextLog: belief changes

Names from the recording (behaviors, capabilities, processes) are escaped as entity path
parts, so any text is a valid single part.
"""

from __future__ import annotations

from dataclasses import dataclass

from rerun import escape_entity_path_part

#: Roots of two recordings shown side by side, in argument order.
DIFF_ROOTS = ("base", "new")

#: Telemetry series derived from each vehicle/state message.
TELEMETRY = ("battery", "altitude", "speed")


@dataclass(frozen=True, slots=True)
class Layout:
    """The entity paths of one recording; `root` is "" (top of the tree) or a name."""

    root: str = ""
    label: str = ""

    def path(self, *parts: str) -> str:
        prefix = f"/{escape_entity_path_part(self.root)}" if self.root else ""
        return prefix + "".join(f"/{part}" for part in parts)

    @property
    def origin(self) -> str:
        return self.path() or "/"

    # -- the 3D scene ------------------------------------------------------------------
    @property
    def world(self) -> str:
        return self.path("world")

    @property
    def markers(self) -> str:
        return self.path("world", "markers")

    @property
    def object(self) -> str:
        return self.path("world", "object")

    @property
    def vehicle(self) -> str:
        return self.path("vehicle")

    @property
    def body(self) -> str:
        return self.path("vehicle", "body")

    @property
    def trajectory(self) -> str:
        return self.path("trajectory")

    @property
    def trajectory_line(self) -> str:
        return self.path("trajectory", "line")

    def telemetry(self, name: str) -> str:
        return self.path("telemetry", name)

    # -- behaviors, capabilities, processes --------------------------------------------
    @property
    def behaviors_active(self) -> str:
        return self.path("behaviors", "active")

    @property
    def behaviors_state(self) -> str:
        return self.path("behaviors", "state")

    def behavior_active(self, behavior: str) -> str:
        return self.path("behaviors", "active", escape_entity_path_part(behavior))

    def behavior_state(self, behavior: str) -> str:
        return self.path("behaviors", "state", escape_entity_path_part(behavior))

    @property
    def capabilities(self) -> str:
        return self.path("capabilities")

    def capability(self, name: str) -> str:
        return self.path("capabilities", escape_entity_path_part(name))

    @property
    def processes(self) -> str:
        return self.path("processes")

    def process(self, name: str) -> str:
        return self.path("processes", escape_entity_path_part(name))

    @property
    def properties(self) -> str:
        return self.path("properties")

    def property_state(self, name: str) -> str:
        return self.path("properties", escape_entity_path_part(name))

    # -- text logs ---------------------------------------------------------------------
    @property
    def events(self) -> str:
        return self.path("events")

    @property
    def errors(self) -> str:
        return self.path("errors")

    @property
    def calls(self) -> str:
        return self.path("calls")

    @property
    def mission(self) -> str:
        return self.path("mission")

    @property
    def log(self) -> str:
        return self.path("log")

    @property
    def beliefs(self) -> str:
        return self.path("beliefs")


def layouts_for(labels: list[str]) -> list[Layout]:
    """One recording at the top of the tree; two under `/base` and `/new`."""
    if len(labels) == 1:
        return [Layout("", labels[0])]
    if len(labels) == len(DIFF_ROOTS):
        return [Layout(root, label) for root, label in zip(DIFF_ROOTS, labels, strict=True)]
    raise ValueError(f"view shows one or two recordings, not {len(labels)}")
