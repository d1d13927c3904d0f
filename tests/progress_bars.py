"""A progress factory for tests: it draws nothing and keeps what each bar was told."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field


@dataclass
class Bar:
    description: str
    total: int
    done: int = 0
    steps: list[int] = field(default_factory=list)


class Bars:
    """`bars(description, total)` as the library calls its progress factory; `bars.bars`
    keeps every bar opened, in order."""

    def __init__(self) -> None:
        self.bars: list[Bar] = []

    @contextmanager
    def __call__(self, description: str, total: int) -> Iterator[Callable[[int], None]]:
        bar = Bar(description, total)
        self.bars.append(bar)

        def advance(n: int) -> None:
            bar.done += n
            bar.steps.append(n)

        yield advance
