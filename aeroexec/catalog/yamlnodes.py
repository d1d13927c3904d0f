"""YAML to plain values that remember where they came from.

PyYAML parses the text into events (with the C parser when it is built in); we build
`YNode`s from the events ourselves instead of letting PyYAML's composer and constructor
run, so that:

* no YAML tag is ever executed (only the core schema's tags are accepted);
* aliases are followed under a budget, so an alias bomb fails fast instead of
  expanding a billion nodes, and recursive aliases are refused;
* nesting is handled with an explicit stack: PyYAML's C composer recurses in C and
  crashes the interpreter (SIGSEGV) on ~100,000 nested brackets, its Python composer
  raises RecursionError at ~1,000;
* every value keeps its `file:line:col`, and every mapping key its own mark.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import yaml

from aeroexec.errors import CatalogError, Mark
from aeroexec.gc_pause import paused_gc

try:  # The C parser is much faster on large catalogs; fall back when PyYAML lacks it.
    _Loader: type = yaml.CSafeLoader  # type: ignore[attr-defined]
except AttributeError:  # pragma: no cover - depends on how PyYAML was built
    _Loader = yaml.SafeLoader

HAS_C_LOADER = _Loader is not yaml.SafeLoader

_CORE = "tag:yaml.org,2002:"
_SCALAR_TAGS = {_CORE + t for t in ("str", "int", "float", "bool", "null")}
_SEQ_TAG = _CORE + "seq"
_MAP_TAG = _CORE + "map"
_MERGE_TAG = _CORE + "merge"
#: Nodes visited per document, aliases counted each time they are followed. Above what
#: the input cap (16 MB, aeroexec.inputs.TEXT_LIMIT) admits of any real catalog (about
#: 95,000 nodes per MB: 1.6 million) or of the hostile one of issue 23 (1.8 million
#: distinct list names), below what a list of one-letter names could pack into 16 MB
#: (8 million, at ~130 bytes of memory each), so that verify stays under 500 MB; and a
#: "billion laughs" stops in milliseconds (an alias costs the size of what it names,
#: computed once, not a walk of it). benchmarks/verify_hostile.py measures both ends.
DEFAULT_NODE_BUDGET = 2_500_000
#: A catalog is 6 levels deep; the limit keeps recursive consumers of `YNode`
#: (`plain()`, `==`) far from Python's recursion limit.
MAX_DEPTH = 200


_NO_KEY_MARKS: dict[str, Mark] = {}


class YNode:
    """A YAML value with its mark. `value` is dict[str, YNode], list[YNode] or a scalar.

    A plain slotted class rather than a frozen dataclass: a large catalog builds hundreds
    of thousands of them, and a frozen dataclass's `__init__` costs four times as much.
    Treat instances as immutable.

    Most nodes are scalars in lists, so a node holds only what every node has; what
    only some have lives in subclasses (`YNode.at` makes the right one): a mapping's key marks
    and duplicate keys (`_YMapping`), a boolean's own text (`_YWord`). The others read
    the class defaults. (A list a million names long is a million nodes: each slot less
    is 8 MB less.)
    """

    __slots__ = ("column", "file", "line", "value")

    #: Mark of each key of a mapping (an empty dict, shared, for other nodes).
    key_marks: dict[str, Mark] = _NO_KEY_MARKS
    #: Keys written twice in a mapping, with the mark of the repetition.
    duplicate_keys: tuple[tuple[str, Mark], ...] = ()
    #: The text of a plain scalar that YAML 1.1 resolved to a boolean (`ON`, `yes`,
    #: `TRUE`...): Aerostack's yaml-cpp loaders read such values as strings and compare
    #: them with "TRUE", so `allowed_values: [ON, OFF]` are two symbols there.
    raw: str | None = None

    def __init__(self, value: Any, file: str, line: int, column: int) -> None:
        # The mark's parts, not a Mark: one object less per node (and no frozen
        # dataclass's __init__ per scalar while loading); `mark` builds it when asked.
        self.value = value
        self.file = file
        self.line = line
        self.column = column

    @staticmethod
    def at(
        value: Any,
        mark: Mark,
        key_marks: dict[str, Mark] | None = None,
        duplicate_keys: tuple[tuple[str, Mark], ...] = (),
        raw: str | None = None,
    ) -> YNode:
        """A node of the class its extras need (a mapping's keys, a boolean's text)."""
        where = (mark.file, mark.line, mark.column)
        if key_marks is not None or duplicate_keys:
            return _YMapping(value, *where, key_marks, duplicate_keys)
        if raw is not None:
            return _YWord(value, *where, raw)
        return YNode(value, *where)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, YNode):
            return NotImplemented
        return (self.value, self.mark, self.duplicate_keys) == (
            other.value,
            other.mark,
            other.duplicate_keys,
        )

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"YNode(value={self.value!r}, mark={self.mark!r})"

    @property
    def mark(self) -> Mark:
        return Mark(self.file, self.line, self.column)

    @property
    def text(self) -> Any:
        """The value as yaml-cpp's `as<std::string>()` sees a boolean: its own text."""
        return self.raw if self.raw is not None else self.value

    @property
    def is_map(self) -> bool:
        return isinstance(self.value, dict)

    @property
    def is_list(self) -> bool:
        return isinstance(self.value, list)

    def get(self, key: str) -> YNode | None:
        return self.value.get(key) if isinstance(self.value, dict) else None

    def items(self) -> Iterator[tuple[str, YNode]]:
        return iter(self.value.items()) if isinstance(self.value, dict) else iter(())

    def plain(self) -> Any:
        """The value without marks (for display and JSON)."""
        if isinstance(self.value, dict):
            return {k: v.plain() for k, v in self.value.items()}
        if isinstance(self.value, list):
            return [v.plain() for v in self.value]
        return self.value


class _YMapping(YNode):
    """A mapping's node: with its keys' marks and repeated keys."""

    __slots__ = ("duplicate_keys", "key_marks")

    def __init__(
        self,
        value: Any,
        file: str,
        line: int,
        column: int,
        key_marks: dict[str, Mark] | None = None,
        duplicate_keys: tuple[tuple[str, Mark], ...] = (),
    ) -> None:
        super().__init__(value, file, line, column)
        self.key_marks = {} if key_marks is None else key_marks
        self.duplicate_keys = duplicate_keys


class _YWord(YNode):
    """A scalar YAML 1.1 read as a boolean, with the text it was written as."""

    __slots__ = ("raw",)

    def __init__(self, value: Any, file: str, line: int, column: int, raw: str | None) -> None:
        super().__init__(value, file, line, column)
        self.raw = raw


def _mark(file: str, mark: Any) -> Mark:
    return Mark(file, mark.line + 1, mark.column + 1)


class _Open:
    """A sequence or mapping whose end event has not arrived yet."""

    __slots__ = (
        "anchor",
        "column",
        "duplicates",
        "items",
        "key",
        "key_mark",
        "key_marks",
        "line",
        "mapping",
        "start",
    )

    def __init__(
        self, line: int, column: int, anchor: str | None, mapping: bool, start: int
    ) -> None:
        self.line = line
        self.column = column
        self.anchor = anchor
        #: The node budget before this collection: what it spent by its end is its size
        #: (itself, and everything in it, aliases at what they expand to).
        self.start = start
        self.mapping = mapping
        self.items: dict[str, YNode] | list[YNode] = {} if mapping else []
        self.key_marks: dict[str, Mark] = {}
        self.duplicates: list[tuple[str, Mark]] = []
        # A mapping's key waiting for its value (None: the next scalar is a key): its
        # name and mark only, no node of its own.
        self.key: str | None = None
        self.key_mark: Mark | None = None

    def close(self, file: str) -> YNode:
        if not self.mapping:
            return YNode(self.items, file, self.line, self.column)
        return _YMapping(
            self.items, file, self.line, self.column, self.key_marks, tuple(self.duplicates)
        )


class _Builder:
    def __init__(self, loader: Any, file: str, budget: int) -> None:
        self.loader = loader
        self.file = file
        self.budget = budget
        self.constructor = yaml.constructor.SafeConstructor()
        self.anchors: dict[str, tuple[YNode, int]] = {}
        self.open_anchors: set[str] = set()
        # Catalogs repeat the same few scalars ("no", "15", list names) thousands of times.
        self.scalars: dict[tuple[Any, ...], Any] = {}

    def spend(self, cost: int, mark: Mark) -> None:
        self.budget -= cost
        if self.budget < 0:
            raise CatalogError(
                "document expands to too many nodes (alias bomb?); refusing to expand it", mark
            )

    def document(self) -> YNode | None:
        loader = self.loader
        loader.get_event()  # StreamStartEvent
        if loader.check_event(yaml.StreamEndEvent):
            return None
        loader.get_event()  # DocumentStartEvent
        root = self.node()
        loader.get_event()  # DocumentEndEvent
        if not loader.check_event(yaml.StreamEndEvent):
            raise CatalogError(
                "invalid YAML: expected a single document, but found another document",
                _mark(self.file, loader.peek_event().start_mark),
            )
        return root

    def node(self) -> YNode:
        """Build the next node from the events, without recursion.

        The hot loop of loading a large catalog: one pass per event, so the common cases
        (scalars, mapping keys, collection ends) are written out inline, and a node
        keeps its line and column without a `Mark` built for it.
        """
        get_event = self.loader.get_event
        file = self.file
        scalar_event, alias_event = yaml.ScalarEvent, yaml.AliasEvent
        mapping_start = yaml.MappingStartEvent
        end_events = (yaml.SequenceEndEvent, yaml.MappingEndEvent)
        scalars = self.scalars
        # PyYAML keys its implicit type resolvers (bool, int, float, null...) by the
        # first character of the text; a plain scalar starting with another one is a
        # string, and needs neither the resolver nor the constructor.
        implicit_resolvers = self.loader.yaml_implicit_resolvers
        plain_words = None not in implicit_resolvers  # no resolver for every text
        stack: list[_Open] = []
        parent: _Open | None = None  # stack[-1]
        node: YNode
        while True:
            event = get_event()
            kind = type(event)
            if kind is scalar_event:
                start = event.start_mark
                line, column = start.line + 1, start.column + 1
                self.budget -= 1
                if self.budget < 0:
                    self.spend(0, Mark(file, line, column))
                text = event.value
                if (
                    plain_words
                    and event.tag is None
                    and text
                    and text[0] not in implicit_resolvers
                    and event.implicit[0]
                ):
                    value = text  # a plain word no implicit type can start with: a str
                else:
                    key = (event.tag, text, event.implicit)
                    if key in scalars:
                        value = scalars[key]
                    else:
                        value = self.scalar(event, Mark(file, line, column))
                if event.anchor is None and parent is not None:
                    # The usual case, attached to its parent here.
                    name = parent.key
                    if parent.mapping and name is None:  # a key: a name and a mark
                        parent.key = value if value.__class__ is str else str(value)
                        parent.key_mark = Mark(file, line, column)
                        continue
                    node = (
                        _YWord(value, file, line, column, text)
                        if value is True or value is False
                        else YNode(value, file, line, column)
                    )
                    if not parent.mapping:
                        parent.items.append(node)  # type: ignore[union-attr]
                        continue
                    items = parent.items
                    if name in items:
                        parent.duplicates.append((name, parent.key_mark))  # type: ignore[arg-type]
                    items[name] = node  # type: ignore[call-overload]
                    parent.key_marks[name] = parent.key_mark  # type: ignore[assignment]
                    parent.key = None
                    continue
                node = (
                    _YWord(value, file, line, column, text)
                    if value is True or value is False
                    else YNode(value, file, line, column)
                )
                size = 1
                if event.anchor is not None:
                    self.remember(event.anchor, (node, 1))
            elif kind in end_events:
                closed = stack.pop()
                parent = stack[-1] if stack else None
                node = closed.close(file)
                size = closed.start - self.budget
                if closed.anchor is not None:
                    self.open_anchors.discard(closed.anchor)
                    self.remember(closed.anchor, (node, size))
            elif kind is alias_event:
                start = event.start_mark
                mark = Mark(file, start.line + 1, start.column + 1)
                found, size = self.alias(event)
                self.spend(size, mark)
                # A reference through an alias is reported where it is used, not at
                # the anchor (the nodes inside a collection keep their own marks).
                keys = found.key_marks if isinstance(found, _YMapping) else None
                node = YNode.at(found.value, mark, keys, found.duplicate_keys, found.raw)
            else:  # SequenceStartEvent / MappingStartEvent
                mapping = kind is mapping_start
                start = event.start_mark
                line, column = start.line + 1, start.column + 1
                self.budget -= 1
                if self.budget < 0:
                    self.spend(0, Mark(file, line, column))
                if event.tag is not None:  # an untagged collection is a map or a seq
                    self.collection_tag(event, mapping, Mark(file, line, column))
                if parent is not None and parent.key is None and parent.mapping:
                    raise CatalogError("a mapping key must be a scalar", Mark(file, line, column))
                if len(stack) >= MAX_DEPTH:
                    raise CatalogError(
                        f"nested more than {MAX_DEPTH} levels deep", Mark(file, line, column)
                    )
                anchor = event.anchor
                if anchor is not None:
                    self.check_anchor(anchor, Mark(file, line, column))
                    self.open_anchors.add(anchor)
                parent = _Open(line, column, anchor, mapping, self.budget + 1)
                stack.append(parent)
                continue
            if parent is None:
                return node
            if not parent.mapping:
                parent.items.append(node)  # type: ignore[union-attr]
            elif parent.key is None:
                if isinstance(node.value, (dict, list)):
                    raise CatalogError("a mapping key must be a scalar", node.mark)
                parent.key = str(node.value)
                parent.key_mark = node.mark
            else:
                name = parent.key
                items = parent.items
                key_mark = parent.key_mark
                assert key_mark is not None
                if name in items:
                    parent.duplicates.append((name, key_mark))
                items[name] = node  # type: ignore[call-overload]
                parent.key_marks[name] = key_mark
                parent.key = None

    def alias(self, event: Any) -> tuple[YNode, int]:
        mark = _mark(self.file, event.start_mark)
        if event.anchor in self.open_anchors:
            raise CatalogError("recursive alias: a node contains itself", mark)
        found = self.anchors.get(event.anchor)
        if found is None:
            raise CatalogError(f"invalid YAML: found undefined alias {event.anchor!r}", mark)
        return found

    def check_anchor(self, anchor: str | None, mark: Mark) -> None:
        # PyYAML's composer refuses a redefined anchor too; keep its behavior.
        if anchor is not None and (anchor in self.anchors or anchor in self.open_anchors):
            raise CatalogError(f"invalid YAML: found duplicate anchor {anchor!r}", mark)

    def remember(self, anchor: str | None, built: tuple[YNode, int]) -> None:
        if anchor is not None:
            self.check_anchor(anchor, built[0].mark)
            self.anchors[anchor] = built

    def collection_tag(self, event: Any, mapping: bool, mark: Mark) -> None:
        kind = yaml.MappingNode if mapping else yaml.SequenceNode
        tag = event.tag
        if tag is None or tag == "!":
            tag = self.loader.resolve(kind, None, event.implicit)
        if tag != (_MAP_TAG if mapping else _SEQ_TAG):
            raise self.refused(tag, mark)

    def refused(self, tag: str, mark: Mark) -> CatalogError:
        return CatalogError(f"YAML tag {tag!r} is not allowed (aeroexec never executes tags)", mark)

    def scalar(self, event: Any, mark: Mark) -> Any:
        key = (event.tag, event.value, event.implicit)
        if key in self.scalars:
            return self.scalars[key]
        tag = event.tag
        if tag is None or tag == "!":
            tag = self.loader.resolve(yaml.ScalarNode, event.value, event.implicit)
        if tag == _MERGE_TAG:
            raise CatalogError("YAML merge keys ('<<') are not supported", mark)
        if tag not in _SCALAR_TAGS:
            raise self.refused(tag, mark)
        node = yaml.ScalarNode(tag, event.value, event.start_mark, event.end_mark)
        try:
            # Call the tag's constructor directly: `construct_object` would keep every
            # node in its memo for the document's lifetime.
            value = self.constructor.yaml_constructors[tag](self.constructor, node)
        except (yaml.YAMLError, ValueError, OverflowError, KeyError) as exc:
            # KeyError: `!!bool xyz`; ValueError: `!!int xyz`, or an int of 5,000 digits.
            problem = "not a boolean" if isinstance(exc, KeyError) else " ".join(str(exc).split())
            raise CatalogError(f"bad scalar {short_repr(event.value)}: {problem}", mark) from None
        self.scalars[key] = value
        return value


def short_repr(value: object, limit: int = 40) -> str:
    """`value` as a message shows it: a word as its repr, anything cut after `limit`
    characters (a hostile file's 100 KB word is not echoed whole, once per finding)."""
    if isinstance(value, str):
        return repr(value if len(value) <= limit else value[:limit] + "...")
    text = repr(value)
    return text if len(text) <= limit else text[:limit] + "..."


def _offset_mark(file: str, text: str, offset: int) -> Mark:
    line = text.count("\n", 0, offset) + 1
    return Mark(file, line, offset - (text.rfind("\n", 0, offset) + 1) + 1)


def _reader_error(exc: yaml.reader.ReaderError, text: str, file: str) -> CatalogError:
    position = exc.position
    if not issubclass(_Loader, yaml.reader.Reader):
        # libyaml counts bytes of the UTF-8 encoding, Python's reader counts characters.
        position = len(text.encode("utf-8")[:position].decode("utf-8", "ignore"))
    character = exc.character
    shown = f"#x{character:04x}" if isinstance(character, int) else repr(character)
    return CatalogError(
        f"invalid YAML: unacceptable character {shown}: {exc.reason}",
        _offset_mark(file, text, position),
    )


def load_yaml(text: str, file: str, *, budget: int = DEFAULT_NODE_BUDGET) -> YNode | None:
    """Parse one YAML document into `YNode`s; `None` for an empty document.

    Raises `CatalogError` (with `file:line:col`) for syntax errors, several documents,
    disallowed tags, alias bombs, recursive aliases and too deep nesting.
    """
    loader = None
    try:
        loader = _Loader(text)  # the pure-Python reader checks characters here already
        with paused_gc():
            return _Builder(loader, file, budget).document()
    except yaml.reader.ReaderError as exc:
        raise _reader_error(exc, text, file) from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = Mark(file, mark.line + 1, mark.column + 1) if mark else Mark(file)
        problem = " ".join((exc.problem or exc.context or "invalid YAML").split())
        raise CatalogError(f"invalid YAML: {problem}", where) from None
    except yaml.YAMLError as exc:
        problem = " ".join(str(exc).split())
        raise CatalogError(f"invalid YAML: {problem}", Mark(file, 1, 1)) from None
    finally:
        if loader is not None:
            loader.dispose()
