"""Which rules a run reports, as ruff decides it: `select`, `extend-select`, `ignore`.

A selector is a rule code (`AX711`) or a prefix of codes (`AX7`, `AX71`, `AX`), or
`ALL`. Settings come in layers — the project configuration first, then the command line
— and each layer is applied over the previous one:

* `select` (when the layer gives it) starts again from exactly what it names;
* `extend-select` adds to what is selected;
* `ignore` removes.

Inside one layer the most specific selector wins (`--select AX7 --ignore AX71` keeps
AX70x, drops AX71x; `--ignore AX7 --extend-select AX711` keeps AX711); between a
selector and an ignore of the same length, the ignore wins. Without any layer every
rule is reported.

Per-file ignores (`{"missions/legacy_*.py" = ["AX708"]}`) drop codes for the files a
glob pattern matches (against the path relative to the configuration's directory, and
as given).
"""

from __future__ import annotations

import fnmatch
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath

from aeroexec.errors import AeroexecError
from aeroexec.verifier.registry import all_rules, suggest_code

ALL = "ALL"


@dataclass(frozen=True, slots=True)
class SelectionLayer:
    """One source of settings (the configuration, or the command line)."""

    select: tuple[str, ...] | None = None
    extend_select: tuple[str, ...] = ()
    ignore: tuple[str, ...] = ()


@dataclass(frozen=True)
class RuleSelection:
    layers: tuple[SelectionLayer, ...] = ()
    #: glob pattern -> selectors ignored in the files it matches.
    per_file_ignores: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    #: The directory per-file patterns are relative to (the configuration's).
    root: Path | None = None

    def __post_init__(self) -> None:
        codes = _known_codes()
        for layer in self.layers:
            for selector in (*(layer.select or ()), *layer.extend_select, *layer.ignore):
                check_selector(selector, codes)
        for selectors in self.per_file_ignores.values():
            for selector in selectors:
                check_selector(selector, codes)
        object.__setattr__(self, "_enabled", _resolve(self.layers, codes))
        object.__setattr__(self, "_known", codes)
        object.__setattr__(self, "_files", {})

    @property
    def everything(self) -> bool:
        """Whether every rule is reported everywhere (nothing to filter)."""
        return not self.per_file_ignores and self.enabled_codes() >= self._known  # type: ignore[attr-defined]

    def enabled_codes(self) -> frozenset[str]:
        return self._enabled  # type: ignore[attr-defined,no-any-return]

    def enabled(self, code: str, file: str = "") -> bool:
        known: frozenset[str] = self._known  # type: ignore[attr-defined]
        if code not in self._enabled and code in known:  # type: ignore[attr-defined]
            return False
        if file and self.per_file_ignores:
            ignored = self._ignored_in(file)
            if any(_matches(selector, code) for selector in ignored):
                return False
        return True

    def _ignored_in(self, file: str) -> tuple[str, ...]:
        cache: dict[str, tuple[str, ...]] = self._files  # type: ignore[attr-defined]
        if file not in cache:
            names = {PurePosixPath(Path(file).as_posix()).as_posix()}
            if self.root is not None:
                try:
                    relative = Path(file).resolve().relative_to(self.root.resolve())
                    names.add(relative.as_posix())
                except (ValueError, OSError):
                    pass
            cache[file] = tuple(
                selector
                for pattern, selectors in self.per_file_ignores.items()
                if any(_glob(name, pattern) for name in names)
                for selector in selectors
            )
        return cache[file]


def _glob(name: str, pattern: str) -> bool:
    # ruff's patterns match a file anywhere below a directory pattern too.
    return fnmatch.fnmatchcase(name, pattern) or fnmatch.fnmatchcase(name, f"*/{pattern}")


def _matches(selector: str, code: str) -> bool:
    return selector == ALL or code.startswith(selector)


def _specificity(selector: str) -> int:
    return 0 if selector == ALL else len(selector)


def _known_codes() -> frozenset[str]:
    return frozenset(rule.code for rule in all_rules())


def check_selector(selector: str, codes: Iterable[str] | None = None) -> None:
    """`AeroexecError` unless `selector` is `ALL` or a prefix of some rule's code."""
    known = _known_codes() if codes is None else codes
    if selector == ALL or any(code.startswith(selector) for code in known):
        return
    raise AeroexecError(f"unknown rule selector {selector!r}{suggest_code(selector)}")


def _resolve(layers: Sequence[SelectionLayer], codes: frozenset[str]) -> frozenset[str]:
    enabled = set(codes)
    for layer in layers:
        positive = (*(layer.select or ()), *layer.extend_select)
        for code in codes:
            best_on = max((_specificity(s) for s in positive if _matches(s, code)), default=-1)
            best_off = max((_specificity(s) for s in layer.ignore if _matches(s, code)), default=-1)
            if best_off >= 0 and best_off >= best_on:
                enabled.discard(code)
            elif best_on >= 0:
                enabled.add(code)
            elif layer.select is not None:
                enabled.discard(code)  # a new `select` names everything that stays
    return frozenset(enabled)


def split_selectors(values: Iterable[str]) -> tuple[str, ...]:
    """Selectors as the command line gives them: repeatable, each comma-separated."""
    return tuple(
        part.strip().upper() for value in values for part in value.split(",") if part.strip()
    )
