"""PAY_ATTENTION_TO_VISUAL_MARKERS (and the thesis' shorter PAY_ATTENTION)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from aeroexec.executive.behavior import Behavior, Finished
from aeroexec.executive.beliefs import Compound


class PayAttentionToVisualMarkers(Behavior):
    """Recurrent: every tick, remember each marker the camera sees as the belief
    `visual_marker(ID)`. Beliefs accumulate (a marker seen once stays known), which is
    what WAIT UNTIL_OBSERVED_VISUAL_MARKER and missions ask about. Never ends by itself."""

    name = "PAY_ATTENTION_TO_VISUAL_MARKERS"
    argument_names = ()

    def on_start(self, args: Mapping[str, Any]) -> None:
        self._look()

    def on_run(self) -> Finished | None:
        self._look()
        return None

    def _look(self) -> None:
        for marker in self.vehicle.visible_markers():
            if self.beliefs.add(Compound("visual_marker", (marker,))):
                self.log(f"marker {marker} observed")


class PayAttention(PayAttentionToVisualMarkers):
    """The name the thesis' Appendix A catalog uses for the same behavior."""

    name = "PAY_ATTENTION"
