"""Did-you-mean suggestions that stay fast on 10,000-name catalogs.

`difflib.get_close_matches` compares the word with every candidate (about 5 µs each),
which is fine for the thesis' twelve behaviors and far too slow for a large catalog
with many misspellings. For large pools a trigram index picks a few dozen likely
candidates first; difflib then decides among them, so the suggestion is the one difflib
would make in all but contrived cases. Names that extend a known name at a word
boundary (`PAY_ATTENTION_TO_VISUAL_MARKERS` for `PAY_ATTENTION`) are suggested too.
"""

from __future__ import annotations

import difflib
from collections import Counter
from collections.abc import Iterable

#: Pools up to this size are searched exhaustively by difflib.
SMALL_POOL = 300
_SHORTLIST = 40
#: difflib similarity a suggestion needs (0.6 suggests GO_TO_POINT for LOOK_AT_POINT;
#: real misspellings score above 0.9).
CUTOFF = 0.8
_POSTINGS_BUDGET = 8_000


def _small_difference(a: str, b: str) -> bool:
    """Past their common prefix and suffix, do the names differ only a little? Keeps
    `SELF_LOCALIZE_BY_LIDAR` from suggesting `SELF_LOCALIZE_BY_ODOMETRY`."""
    start = 0
    while start < min(len(a), len(b)) and a[start] == b[start]:
        start += 1
    end = 0
    while end < min(len(a), len(b)) - start and a[-1 - end] == b[-1 - end]:
        end += 1
    rest_a, rest_b = a[start : len(a) - end], b[start : len(b) - end]
    if max(len(rest_a), len(rest_b)) <= 3:
        return True
    return difflib.SequenceMatcher(None, rest_a, rest_b).ratio() >= 0.5


def _trigrams(word: str) -> set[str]:
    padded = f"  {word.casefold()} "
    return {padded[i : i + 3] for i in range(len(padded) - 2)}


#: Words whose suggestion a `Suggester` remembers.
CACHE_SIZE = 65_536


class Suggester:
    """Suggests a close name from a fixed pool (kept in the given order)."""

    def __init__(self, names: Iterable[str]) -> None:
        self.names = list(dict.fromkeys(names))
        self._folded = {n.casefold(): n for n in reversed(self.names)}
        self._known = set(self.names)
        self._index: dict[str, list[int]] | None = None
        self._cache: dict[str, str | None] = {}

    def best(self, word: str) -> str | None:
        if word not in self._cache:
            if len(self._cache) >= CACHE_SIZE:
                # A catalog can misspell a million distinct names: memory stays bounded
                # (a name asked about again is usually asked about soon after).
                self._cache.clear()
            self._cache[word] = self._best(word)
        return self._cache[word]

    def hint(self, word: str) -> str:
        """` (did you mean 'X'?)` or ''."""
        found = self.best(word)
        return f" (did you mean '{found}'?)" if found else ""

    def _best(self, word: str) -> str | None:
        """Compared ignoring case: `coordinats` finds `COORDINATES`."""
        if not self.names:
            return None
        folded = self._folded.get(word.casefold())
        if folded is not None and folded != word:
            return folded
        pool = self.names if len(self.names) <= SMALL_POOL else self._shortlist(word)
        candidates = {n.casefold(): n for n in reversed(pool) if n != word}
        wanted = word.casefold()
        for close in difflib.get_close_matches(wanted, list(candidates), n=3, cutoff=CUTOFF):
            if _small_difference(wanted, close):
                return candidates[close]
        return self._by_prefix(word)

    def _by_prefix(self, word: str) -> str | None:
        """A known name of two or more words that `word` extends at a `_` boundary
        (`PAY_ATTENTION_TO_VISUAL_MARKERS` -> `PAY_ATTENTION`; `LAND_ON_...` does not
        suggest `LAND`)."""
        parts = word.split("_")
        for cut in range(len(parts) - 1, 1, -1):
            candidate = "_".join(parts[:cut])
            if candidate in self._known:
                return candidate
        return None

    def _shortlist(self, word: str) -> list[str]:
        index = self._build_index()
        grams = sorted(_trigrams(word), key=lambda g: len(index.get(g, ())))
        counts: Counter[int] = Counter()
        spent = 0
        for gram in grams:
            postings = index.get(gram, ())
            if spent and spent + len(postings) > _POSTINGS_BUDGET:
                break
            counts.update(postings)
            spent += len(postings)
        return [self.names[i] for i, _ in counts.most_common(_SHORTLIST)]

    def _build_index(self) -> dict[str, list[int]]:
        if self._index is None:
            index: dict[str, list[int]] = {}
            for i, name in enumerate(self.names):
                for gram in _trigrams(name):
                    index.setdefault(gram, []).append(i)
            self._index = index
        return self._index
