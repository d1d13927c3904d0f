"""The layout the viewer opens on: the flight in 3D, the behavior timeline, capability
reference counts, and the event log, rather than Rerun's automatic guess.

    +----------------------------------+------------------------------------+
    | Flight (3D: world markers,       | Behaviors (state timeline: one     |
    |   vehicle pose, trajectory up    |   lane per behavior, a bar per     |
    |   to the time cursor)            |   activation)                      |
    |----------------------------------|------------------------------------|
    | tabs: Events & errors | Service  | tabs: Capability references |      |
    |   calls | Mission | Log |        |   Behavior active (1/0) |          |
    |   Beliefs                        |   Telemetry | Processes            |
    +----------------------------------+------------------------------------+

With two recordings, the 3D view and the behavior timeline show both (lanes and
trajectories of `/base` and `/new` together, on one `sim_time` axis); the plots and logs
come in one tab per recording.
"""

from __future__ import annotations

import rerun.blueprint as rrb

from aeroexec.viz.columns import SIM_TIME
from aeroexec.viz.layout import Layout


def _title(name: str, layout: Layout, several: bool) -> str:
    return f"{name} ({layout.label})" if several and layout.label else name


def _scene(layouts: list[Layout]) -> rrb.Spatial3DView:
    contents: list[str] = []
    for layout in layouts:
        contents += [f"+ {layout.world}/**", f"+ {layout.vehicle}/**", f"+ {layout.trajectory}/**"]
    return rrb.Spatial3DView(
        name="Flight",
        origin="/",
        contents=contents,
        # The trajectory grows with the time cursor: everything up to it is drawn.
        time_ranges=rrb.VisibleTimeRange(
            SIM_TIME,
            start=rrb.TimeRangeBoundary.infinite(),
            end=rrb.TimeRangeBoundary.cursor_relative(),
        ),
    )


def _behaviors(layouts: list[Layout]) -> rrb.StateTimelineView:
    """One lane per behavior, and one per violated property (run/fly --spec) under them."""
    contents = [f"+ {layout.behaviors_state}/**" for layout in layouts]
    contents += [f"+ {layout.properties}/**" for layout in layouts]
    return rrb.StateTimelineView(name="Behaviors", origin="/", contents=contents)


def _logs(layout: Layout, several: bool) -> list[rrb.View]:
    return [
        rrb.TextLogView(
            name=_title("Events & errors", layout, several),
            origin=layout.origin,
            contents=[f"+ {layout.events}", f"+ {layout.errors}"],
        ),
        rrb.TextLogView(name=_title("Service calls", layout, several), origin=layout.calls),
        rrb.TextLogView(name=_title("Mission", layout, several), origin=layout.mission),
        rrb.TextLogView(name=_title("Log", layout, several), origin=layout.log),
        rrb.TextLogView(name=_title("Beliefs", layout, several), origin=layout.beliefs),
    ]


def _plots(layouts: list[Layout], several: bool) -> list[rrb.View]:
    """Capability counts first (the behavior timeline above already says which behaviors
    run; the counts say what they hold), then the 1/0 tracks, telemetry, processes."""
    views: list[rrb.View] = []
    for layout in layouts:
        views.append(
            rrb.TimeSeriesView(
                name=_title("Capability references", layout, several), origin=layout.capabilities
            )
        )
    for layout in layouts:
        views.append(
            rrb.TimeSeriesView(
                name=_title("Behavior active (1/0)", layout, several),
                origin=layout.behaviors_active,
            )
        )
    for layout in layouts:
        views.append(
            rrb.TimeSeriesView(
                name=_title("Telemetry", layout, several), origin=layout.path("telemetry")
            )
        )
    for layout in layouts:
        views.append(
            rrb.StateTimelineView(
                name=_title("Processes", layout, several), origin=layout.processes
            )
        )
    return views


def build_blueprint(layouts: list[Layout]) -> rrb.Blueprint:
    several = len(layouts) > 1
    logs: list[rrb.View] = []
    for layout in layouts:
        logs += _logs(layout, several)
    left = rrb.Vertical(_scene(layouts), rrb.Tabs(*logs), row_shares=[3, 2])
    right = rrb.Vertical(_behaviors(layouts), rrb.Tabs(*_plots(layouts, several)))
    return rrb.Blueprint(
        rrb.Horizontal(left, right, column_shares=[3, 2]),
        rrb.TimePanel(timeline=SIM_TIME),
        collapse_panels=False,
    )
