"""Rebuild the service call tree from completed calls, streaming.

A recording writes each call when it returns, so children come before their parent
(`parent_seq` names the call a call happened inside; a root call has none). `CallTree`
holds the calls of each tree until its root returns, then hands the whole tree back in
start order (`seq`) with each call's depth. Memory is one unfinished tree, plus the
depths of the last few finished calls, for a call that returns after its parent did.
What is still held at the end (a file cut before a root returned) comes out of `drain`,
each partial tree at depth 1 (below a parent the file does not hold).
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Iterator

from aeroexec.recording.reader import RecordedCall

#: How many finished calls keep their depth for late children.
RECENT_CALLS = 4096


class CallTree:
    def __init__(self, recent: int = RECENT_CALLS) -> None:
        self._pending: dict[int, RecordedCall] = {}
        self._children: dict[int, list[int]] = {}
        self._depths: OrderedDict[int, int] = OrderedDict()
        self._recent = recent

    @property
    def pending(self) -> int:
        return len(self._pending)

    def add(self, call: RecordedCall) -> list[tuple[RecordedCall, int]]:
        """The calls that can be placed now, in start order, with their depth (0 for a
        root call)."""
        parent = call.parent_seq
        if parent is None:
            return list(self._emit(call, 0))
        known = self._depths.get(parent)
        if known is not None:  # its parent already returned: place it at once
            return list(self._emit(call, known + 1))
        self._pending[call.seq] = call
        self._children.setdefault(parent, []).append(call.seq)
        return []

    def drain(self) -> list[tuple[RecordedCall, int]]:
        """What is left: trees whose root call the file does not hold."""
        out: list[tuple[RecordedCall, int]] = []
        tops = sorted(
            seq
            for seq, call in self._pending.items()
            if call.parent_seq is None or call.parent_seq not in self._pending
        )
        for seq in tops:
            call = self._pending.pop(seq, None)
            if call is not None:
                out.extend(self._emit(call, 1))
        self._pending.clear()
        self._children.clear()
        return out

    def _emit(self, root: RecordedCall, depth: int) -> Iterator[tuple[RecordedCall, int]]:
        stack: list[tuple[RecordedCall, int]] = [(root, depth)]
        while stack:
            call, d = stack.pop()
            yield call, d
            self._remember(call.seq, d)
            children = self._children.pop(call.seq, [])
            for seq in sorted(children, reverse=True):
                child = self._pending.pop(seq, None)
                if child is not None:
                    stack.append((child, d + 1))

    def _remember(self, seq: int, depth: int) -> None:
        self._depths[seq] = depth
        self._depths.move_to_end(seq)
        while len(self._depths) > self._recent:
            self._depths.popitem(last=False)
