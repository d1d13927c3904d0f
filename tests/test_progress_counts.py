"""Progress bars count the work that takes the time (issue 17): the bag's messages for
`import`, the decoded messages for `view` -- and reach their total."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from aeroexec.bags import import_bag
from aeroexec.recording import open_recording
from aeroexec.viz.view import write_view

BAG = Path(__file__).resolve().parent / "fixtures" / "bags" / "aerostack_2017_first_view_ros1.bag"


class Bars:
    """A progress factory that keeps (description, total, sum of advances) per bar."""

    def __init__(self) -> None:
        self.bars: list[list[object]] = []

    @contextmanager
    def __call__(self, description: str, total: int) -> Iterator[Callable[[int], None]]:
        bar: list[object] = [description, total, 0, 0]
        self.bars.append(bar)

        def advance(n: int) -> None:
            bar[2] = int(bar[2]) + n  # type: ignore[call-overload]
            bar[3] = int(bar[3]) + 1  # type: ignore[call-overload]

        yield advance


def test_import_counts_the_bag_messages(tmp_path: Path) -> None:
    bars = Bars()
    report = import_bag(BAG, tmp_path / "out.mcap", progress=bars)
    ((name, total, done, calls),) = bars.bars
    assert name == BAG.name
    assert total == done == report.messages > 1000
    assert int(calls) > 1  # along the way, not once at the end  # type: ignore[call-overload]


def test_view_of_an_import_counts_what_it_converts(tmp_path: Path) -> None:
    imported = tmp_path / "imported.mcap"
    import_bag(BAG, imported)
    survey = open_recording(imported).survey()
    bars = Bars()
    write_view([imported], tmp_path / "out.rrd", progress=bars)
    ((_, total, done, _),) = bars.bars
    # The raw ros1 channels are read past, not converted: the bar counts the JSON ones
    # and ends full.
    assert total == done
    assert 0 < int(total) < survey.message_count  # type: ignore[call-overload]
