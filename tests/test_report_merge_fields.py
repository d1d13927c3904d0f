"""A merged shard reads back every field a replay result reports (a field the merge
forgets would vanish from the merged verdict without a word)."""

from __future__ import annotations

from aeroexec.replay.diff import Difference, DiffResult, Tolerance
from aeroexec.replay.engine import ReplayResult
from aeroexec.replay.merge import result_from_dict


def test_every_reported_field_survives_the_round_trip() -> None:
    tolerance = Tolerance()
    difference = Difference("end", "#2 GO_TO_POINT now ends TIME_OUT", 2, "GO_TO_POINT", 2, 2)
    result = ReplayResult(
        recording="flights/a.mcap",
        mode="closed",
        catalog="new.yaml",
        catalog_recorded=False,
        diff=DiffResult("the recording", "the replay", (difference,), 9, tolerance),
        output="out/a.mcap",
        notes=("replayed the recorded mission commands",),
        code_changes=("GO_TO_POINT: pkg.mod:Go source changed (sha256:aa -> sha256:bb)",),
    )
    data = result.as_dict()
    again = result_from_dict(data, tolerance)
    assert again.as_dict() == data
    assert again.code_changes == result.code_changes and not again.equal
