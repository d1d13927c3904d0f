"""The standard behavior library: one class per behavior of the default catalog.

Behaviors use only the `Vehicle` protocol and the beliefs, so they fly the simulator
and a MAVLink autopilot alike. `STANDARD_LIBRARY` maps catalog names to classes; the
`Executive` uses it unless given another library.
"""

from __future__ import annotations

from aeroexec.behaviors.flight import Land, TakeOff
from aeroexec.behaviors.hovering import Flip, KeepHovering, StartHovering
from aeroexec.behaviors.messaging import BroadcastMessage
from aeroexec.behaviors.motion import FollowObjectImage, GoToPoint, StartMoving
from aeroexec.behaviors.perception import PayAttention, PayAttentionToVisualMarkers
from aeroexec.behaviors.rotation import Rotate
from aeroexec.behaviors.waiting import Wait
from aeroexec.executive.behavior import Behavior

_CLASSES: tuple[type[Behavior], ...] = (
    TakeOff,
    Land,
    GoToPoint,
    Rotate,
    StartMoving,
    FollowObjectImage,
    PayAttention,
    PayAttentionToVisualMarkers,
    KeepHovering,
    Wait,
    Flip,
    StartHovering,
    BroadcastMessage,
)

STANDARD_LIBRARY: dict[str, type[Behavior]] = {cls.name: cls for cls in _CLASSES}

__all__ = [
    "STANDARD_LIBRARY",
    "BroadcastMessage",
    "Flip",
    "FollowObjectImage",
    "GoToPoint",
    "KeepHovering",
    "Land",
    "PayAttention",
    "PayAttentionToVisualMarkers",
    "Rotate",
    "StartHovering",
    "StartMoving",
    "TakeOff",
    "Wait",
]
