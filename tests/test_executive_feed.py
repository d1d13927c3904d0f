"""The belief feed runs again only when something it depends on changed (issue 17):
the vehicle state, or the belief store (a mission or behavior may remove a belief the
feed keeps)."""

from __future__ import annotations

from aeroexec.catalog import DEFAULT_CATALOG, load_catalog
from aeroexec.executive import Executive, GenericBehavior, MemoryObserver
from aeroexec.vehicles.null import NullVehicle


def _executive(observer: MemoryObserver | None = None) -> Executive:
    return Executive(
        load_catalog(DEFAULT_CATALOG),
        vehicle=NullVehicle(),
        library={},
        stand_in=GenericBehavior,
        observers=[observer] if observer else [],
    )


def test_a_belief_removed_between_ticks_is_fed_again() -> None:
    ex = _executive()
    ex.step()
    fed = ex.beliefs.texts()
    position = next(text for text in fed if text.startswith("position("))
    assert ex.beliefs.remove(position)
    assert position not in ex.beliefs.texts()
    ex.step()  # same vehicle state, but the store changed: the feed runs
    assert ex.beliefs.texts().count(position) == 1
    assert sorted(ex.beliefs.texts()) == sorted(fed)


def test_unchanged_state_and_beliefs_publish_no_belief_change() -> None:
    observer = MemoryObserver()
    ex = _executive(observer)
    ex.step()
    before = len(observer.topics("beliefs"))
    for _ in range(5):
        ex.step()
    assert len(observer.topics("beliefs")) == before
    assert len(observer.topics("vehicle/state")) == 6  # every tick still publishes it
