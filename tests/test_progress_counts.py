"""Progress bars count the work that takes the time (issue 17): the bag's messages for
`import`, the decoded messages for `view` -- and reach their total."""

from __future__ import annotations

from pathlib import Path

from progress_bars import Bars

from aeroexec.bags import import_bag
from aeroexec.recording import open_recording
from aeroexec.viz.view import write_view

BAG = Path(__file__).resolve().parent / "fixtures" / "bags" / "aerostack_2017_first_view_ros1.bag"


def test_import_counts_the_bag_messages(tmp_path: Path) -> None:
    bars = Bars()
    report = import_bag(BAG, tmp_path / "out.mcap", progress=bars)
    (bar,) = bars.bars
    assert bar.description == BAG.name
    assert bar.total == bar.done == report.messages > 1000
    assert len(bar.steps) > 1  # along the way, not once at the end


def test_view_of_an_import_counts_what_it_converts(tmp_path: Path) -> None:
    imported = tmp_path / "imported.mcap"
    import_bag(BAG, imported)
    survey = open_recording(imported).survey()
    bars = Bars()
    write_view([imported], tmp_path / "out.rrd", progress=bars)
    (bar,) = bars.bars
    # The raw ros1 channels are read past, not converted: the bar counts the JSON ones
    # and ends full.
    assert bar.total == bar.done
    assert 0 < bar.total < survey.message_count
