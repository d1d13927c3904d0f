"""The behavior catalog: descriptors (frozen) and a `Catalog` with indexes built once.

The executive asks the catalog questions on every activation ("which active behaviors
does B preempt?", "which capabilities conflict with C?"). Those answers come from
indexes computed in `Catalog.__post_init__`, so an activation costs O(active set),
never O(catalog).
"""

from __future__ import annotations

from array import array
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from enum import Enum
from typing import overload

from aeroexec.errors import Mark, one_line

DEFAULT_TIMEOUT_S = 15.0
#: The longest timeout the executive can arm: its clock counts nanoseconds in an int64
#: (as ROS and MCAP time do), about 292 years. `.inf` or 1e300 would overflow it.
MAX_TIMEOUT_S = (2**63 - 1) / 1e9
#: The mark of entries built in code rather than read from a file.
IN_MEMORY = Mark("<memory>")


@dataclass(frozen=True, slots=True)
class PackedMarks(Sequence[Mark]):
    """The marks of the items of one list, all in one file, as two arrays of numbers:
    eight bytes an item instead of a `Mark` object and its column's int (about 90).
    (Unsigned 32 bits: the input cap, 16 MB, keeps lines and columns far below.)"""

    file: str
    lines: array[int] = field(default_factory=lambda: array("I"))
    columns: array[int] = field(default_factory=lambda: array("I"))

    def __len__(self) -> int:
        return len(self.lines)

    @overload
    def __getitem__(self, index: int) -> Mark: ...

    @overload
    def __getitem__(self, index: slice) -> Sequence[Mark]: ...

    def __getitem__(self, index: int | slice) -> Mark | Sequence[Mark]:
        if index.__class__ is int:
            return Mark(self.file, self.lines[index], self.columns[index])  # type: ignore[index]
        assert isinstance(index, slice)
        return [self[i] for i in range(*index.indices(len(self)))]


class Marks(Mapping[str, Mark]):
    """The marks of an entry's fields (`timeout`) and of the items of its name lists
    (`incompatible_lists.3`), read as one mapping.

    Each list's marks are kept as one tuple, not under a string key per item: a key per
    name cost a hundred bytes more for every name of a list a million names long (a
    hostile catalog's worst case, within the input size cap).
    """

    __slots__ = ("_fields", "_items")

    def __init__(
        self,
        fields: Mapping[str, Mark] | None = None,
        items: Mapping[str, Sequence[Mark]] | None = None,
    ) -> None:
        # A dict is kept as given, not copied (the loader builds one per entry, and a
        # YAML mapping's key marks never change once read): the caller hands it over.
        self._fields = fields if type(fields) is dict else dict(fields or {})
        self._items = items if type(items) is dict else dict(items or {})

    def __getitem__(self, key: str) -> Mark:
        mark = self.get(key)
        if mark is None:
            raise KeyError(key)
        return mark

    @overload
    def get(self, key: str, /) -> Mark | None: ...

    @overload
    def get(self, key: str, /, default: Mark) -> Mark: ...

    def get(self, key: str, /, default: Mark | None = None) -> Mark | None:
        # Without Mapping.get's KeyError round trip: rules ask for the mark of every
        # item of a list a million names long.
        mark = self._fields.get(key)
        if mark is not None:
            return mark
        head, dot, index = key.rpartition(".")
        if dot and index.isdigit() and index.isascii():
            marks = self._items.get(head)
            if marks is not None:
                position = int(index)
                if position < len(marks):
                    return marks[position]
        return default

    def item(self, field: str, index: int, default: Mark) -> Mark:
        """The mark of item `index` of list `field` (else `default`): `get` without
        writing and parsing the key."""
        marks = self._items.get(field)
        if marks is not None and 0 <= index < len(marks):
            return marks[index]
        return self._fields.get(f"{field}.{index}", default)

    def __iter__(self) -> Iterator[str]:
        yield from self._fields
        for head, marks in self._items.items():
            yield from (f"{head}.{i}" for i in range(len(marks)))

    def __len__(self) -> int:
        return len(self._fields) + sum(len(marks) for marks in self._items.values())

    def __getstate__(self) -> tuple[dict[str, Mark], dict[str, Sequence[Mark]]]:
        return self._fields, self._items

    def __setstate__(self, state: tuple[dict[str, Mark], dict[str, Sequence[Mark]]]) -> None:
        self._fields, self._items = state

    def __repr__(self) -> str:
        return f"Marks({dict(self)!r})"


def item_mark(marks: Mapping[str, Mark], field: str, index: int, default: Mark) -> Mark:
    """The mark of item `index` of the list `field` in `marks`, else `default`."""
    if marks.__class__ is Marks:
        return marks.item(field, index, default)  # type: ignore[attr-defined]
    return marks.get(f"{field}.{index}", default)


class Severity(str, Enum):
    ERROR = "error"
    WARNING = "warning"
    INFO = "info"


@dataclass(frozen=True, slots=True)
class Diagnostic:
    """Something the loader (or the verifier) has to say about a place in a catalog."""

    code: str
    severity: Severity
    message: str
    mark: Mark
    subjects: tuple[str, ...] = ()

    def __str__(self) -> str:
        return one_line(f"{self.mark}: {self.severity.value} {self.code} {self.message}")


class ArgumentKind(str, Enum):
    RANGE = "range"  # numbers in [minimum, maximum], `dimensions` of them
    SYMBOLS = "symbols"  # one of a list of words
    TEXT = "text"  # any string
    INVALID = "invalid"  # a malformed spec: the loader reported it; nothing validates


@dataclass(frozen=True, slots=True)
class ArgumentSpec:
    name: str
    kind: ArgumentKind
    minimum: float | None = None
    maximum: float | None = None
    dimensions: int = 1
    symbols: tuple[str, ...] = ()
    mark: Mark = IN_MEMORY

    def describe(self) -> str:
        """The allowed values as a person reads them: `3 numbers in [-100, 100]`."""
        if self.kind is ArgumentKind.RANGE:
            count = "a number" if self.dimensions == 1 else f"{self.dimensions} numbers"
            return f"{count} in [{_num(self.minimum)}, {_num(self.maximum)}]"
        if self.kind is ArgumentKind.SYMBOLS:
            return "one of " + ", ".join(self.symbols)
        if self.kind is ArgumentKind.TEXT:
            return "text"
        return "(malformed specification)"


def _num(value: float | None) -> str:
    if value is None:
        return "?"
    return str(int(value)) if float(value).is_integer() else repr(float(value))


@dataclass(frozen=True, slots=True)
class BehaviorDescriptor:
    name: str
    timeout: float | None  # seconds; None = no timeout (recurrent behaviors)
    recurrent: bool
    incompatible_lists: tuple[str, ...] = ()
    capabilities: tuple[str, ...] = ()
    arguments: tuple[ArgumentSpec, ...] = ()
    mark: Mark = IN_MEMORY
    #: Marks of individual fields and references, e.g. "timeout", "incompatible_lists.0".
    marks: Mapping[str, Mark] = field(default_factory=dict, compare=False, hash=False)

    def argument(self, name: str) -> ArgumentSpec | None:
        """Case-insensitive lookup: missions write `coordinates` for `COORDINATES`."""
        wanted = name.casefold()
        for spec in self.arguments:
            if spec.name.casefold() == wanted:
                return spec
        return None

    def mark_of(self, key: str) -> Mark:
        return self.marks.get(key, self.mark)

    def item_mark(self, field: str, index: int) -> Mark:
        """`mark_of(f"{field}.{index}")`, for the rules' loops over every item."""
        return item_mark(self.marks, field, index, self.mark)


@dataclass(frozen=True, slots=True)
class BehaviorList:
    name: str
    behaviors: tuple[str, ...]
    mark: Mark = IN_MEMORY
    marks: Mapping[str, Mark] = field(default_factory=dict, compare=False, hash=False)

    def mark_of(self, key: str) -> Mark:
        return self.marks.get(key, self.mark)

    def item_mark(self, field: str, index: int) -> Mark:
        """`mark_of(f"{field}.{index}")`, for the rules' loops over every item."""
        return item_mark(self.marks, field, index, self.mark)


@dataclass(frozen=True, slots=True)
class CapabilityDescriptor:
    name: str
    processes: tuple[str, ...]
    active_by_default: bool = False
    incompatible_capabilities: tuple[str, ...] = ()
    required_capabilities: tuple[str, ...] = ()
    mark: Mark = IN_MEMORY
    marks: Mapping[str, Mark] = field(default_factory=dict, compare=False, hash=False)

    def mark_of(self, key: str) -> Mark:
        return self.marks.get(key, self.mark)

    def item_mark(self, field: str, index: int) -> Mark:
        """`mark_of(f"{field}.{index}")`, for the rules' loops over every item."""
        return item_mark(self.marks, field, index, self.mark)


@dataclass(frozen=True, eq=False)
class Catalog:
    """A loaded catalog. Entries keep file order; the first definition of a name wins."""

    behaviors: Mapping[str, BehaviorDescriptor]
    lists: Mapping[str, BehaviorList]
    capabilities: Mapping[str, CapabilityDescriptor]
    source: str = "<memory>"
    dialect: str = "aeroexec"
    text: str = ""
    diagnostics: tuple[Diagnostic, ...] = ()
    #: Every definition in file order, duplicates included (the verifier reports them).
    all_behaviors: tuple[BehaviorDescriptor, ...] = ()
    all_lists: tuple[BehaviorList, ...] = ()
    all_capabilities: tuple[CapabilityDescriptor, ...] = ()
    #: Marks of top-level sections ("behavior_descriptors", ...), for findings about them.
    section_marks: Mapping[str, Mark] = field(default_factory=dict)

    # Indexes, computed once.
    _preempts: dict[str, frozenset[str]] = field(init=False, repr=False)
    _conflicts: dict[str, frozenset[str]] = field(init=False, repr=False)
    _order: dict[str, int] = field(init=False, repr=False)
    _default_capabilities: tuple[str, ...] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        members: dict[str, frozenset[str]] = {
            name: frozenset(lst.behaviors) for name, lst in self.lists.items()
        }
        preempts: dict[str, frozenset[str]] = {}
        nothing: frozenset[str] = frozenset()
        for name, behavior in self.behaviors.items():
            named = behavior.incompatible_lists
            if len(named) == 1:  # the usual case: the list's own set, shared
                preempts[name] = members.get(named[0], nothing)
                continue
            victims: set[str] = set()
            for list_name in named:
                victims |= members.get(list_name, nothing)
            preempts[name] = frozenset(victims)
        conflicts: dict[str, set[str]] = {name: set() for name in self.capabilities}
        for name, capability in self.capabilities.items():
            for other in capability.incompatible_capabilities:
                conflicts.setdefault(name, set()).add(other)
                conflicts.setdefault(other, set()).add(name)
        object.__setattr__(self, "_preempts", preempts)
        object.__setattr__(self, "_conflicts", {k: frozenset(v) for k, v in conflicts.items()})
        object.__setattr__(self, "_order", {name: i for i, name in enumerate(self.behaviors)})
        object.__setattr__(
            self,
            "_default_capabilities",
            tuple(n for n, c in self.capabilities.items() if c.active_by_default),
        )

    # -- lookups -------------------------------------------------------------------------
    def behavior(self, name: str) -> BehaviorDescriptor | None:
        return self.behaviors.get(name)

    def preempted_by(self, name: str) -> frozenset[str]:
        """Behaviors that `name` stops when it is activated (its incompatible lists)."""
        return self._preempts.get(name, frozenset())

    def conflicts_of(self, capability: str) -> frozenset[str]:
        """Capabilities that cannot be referenced together with `capability` (symmetric)."""
        return self._conflicts.get(capability, frozenset())

    def order_of(self, behavior: str) -> int:
        """Position in the catalog: the stable tie-break of the deterministic core."""
        return self._order.get(behavior, len(self._order))

    @property
    def default_capabilities(self) -> tuple[str, ...]:
        return self._default_capabilities

    def warnings(self) -> tuple[Diagnostic, ...]:
        return tuple(d for d in self.diagnostics if d.severity is not Severity.ERROR)
