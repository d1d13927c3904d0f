"""The static part of the 3D scene: axes convention, the world's markers, the vehicle's
body, and the per-entity styles of the time series (step lines).

The world is the recording's `world.yaml` attachment (what the session flew in); a
recording without one, or with one that does not parse, simply has no markers.
"""

from __future__ import annotations

import rerun as rr

from aeroexec.errors import WorldError
from aeroexec.recording.foxglove import (
    BODY_HALF_SIZE,
    MARKER_COLOR,
    MARKER_HALF_SIZE,
    VEHICLE_COLOR,
)
from aeroexec.recording.reader import Recording, attachment_place
from aeroexec.vehicles.world import World, parse_world
from aeroexec.viz.layout import Layout

WORLD_ATTACHMENT = "world.yaml"

#: Trajectory color per recording (base, new): blue (the Foxglove scene's too), orange.
TRAJECTORY_COLORS = (VEHICLE_COLOR, (244, 140, 40))


def trajectory_color(index: int) -> tuple[int, int, int]:
    return TRAJECTORY_COLORS[index % len(TRAJECTORY_COLORS)]


def recorded_world(recording: Recording) -> tuple[World | None, str | None]:
    """The world the session flew in and, when it cannot be had, why (a note)."""
    attachment = recording.attachment(WORLD_ATTACHMENT)
    if attachment is None:
        return None, f"no {WORLD_ATTACHMENT} attachment: no markers shown"
    try:
        return parse_world(
            attachment.text, attachment_place(recording.name, WORLD_ATTACHMENT)
        ), None
    except WorldError as exc:
        return None, f"{WORLD_ATTACHMENT} attachment unreadable ({exc}): no markers shown"


def log_view_coordinates(stream: rr.RecordingStream) -> None:
    """aeroexec's world frame is ENU: x east, y north, z up."""
    stream.log("/", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)


def log_world(stream: rr.RecordingStream, layout: Layout, world: World) -> None:
    if not world.markers:
        return
    positions = [marker.position for marker in world.markers]
    labels = [f"marker {marker.id}" for marker in world.markers]
    stream.log(
        layout.markers,
        rr.Boxes3D(
            centers=positions,
            half_sizes=[MARKER_HALF_SIZE] * len(positions),
            colors=[MARKER_COLOR] * len(positions),
            labels=labels,
            show_labels=True,
        ),
        static=True,
    )


def log_vehicle_body(
    stream: rr.RecordingStream, layout: Layout, color: tuple[int, int, int]
) -> None:
    stream.log(layout.vehicle, rr.TransformAxes3D(0.5), static=True)
    label = f"vehicle ({layout.label})" if layout.root else "vehicle"
    stream.log(
        layout.body,
        rr.Boxes3D(half_sizes=[BODY_HALF_SIZE], colors=[color], labels=[label]),
        static=True,
    )


def log_series_style(
    stream: rr.RecordingStream, entity: str, name: str, color: tuple[int, int, int] | None = None
) -> None:
    """A step line named `name`: the value holds until the next row. Zoomed out, where
    several rows share a pixel, the plot draws their least and greatest value (a
    vertical stroke), never their average: a level the series never had."""
    stream.log(
        entity,
        rr.SeriesLines(
            names=[name],
            colors=[color] if color else None,
            interpolation_mode="StepAfter",
            aggregation_policy="MinMax",
        ),
        static=True,
    )
