"""Which code ran: per behavior, its class and a hash of its source (for recordings).

A recording carries a metadata record `behaviors` mapping each catalog behavior to
`module:Class sha256:<16 hex digits>` (`stand-in module:Class ...` for an explicit
stand-in), and the source of every developer module those classes come from as an
attachment `behaviors/<module>.py`. Replay compares the recorded record with the code it
runs now and reports "code changed" for each behavior whose class or source differs.

The hash covers the source text of every module that defines a class in the behavior's
class hierarchy (its own module, its base classes' modules, aeroexec's `Behavior`), read
the way Python reads it (universal newlines). It names modules, never paths, so a
package imported from a temporary directory records the same bytes as from anywhere
else. Code a behavior only calls (a helper module it imports) is not covered.
"""

from __future__ import annotations

import hashlib
import sys
from collections.abc import Iterator, Mapping
from dataclasses import dataclass

from aeroexec.catalog.model import Catalog
from aeroexec.plugins.discovery import BehaviorSet, Implementation

#: The metadata record's name, and the prefix of the source attachments.
METADATA_NAME = "behaviors"
ATTACHMENT_PREFIX = "behaviors/"
STAND_IN_PREFIX = "stand-in "
_DIGEST = "sha256:"
_DIGITS = 16


@dataclass(frozen=True, slots=True)
class CodeEntry:
    """What implemented one behavior: `module:Class` and the hash of its sources."""

    reference: str
    digest: str
    stand_in: bool = False

    def text(self) -> str:
        prefix = STAND_IN_PREFIX if self.stand_in else ""
        return f"{prefix}{self.reference} {_DIGEST}{self.digest}"

    @classmethod
    def parse(cls, text: str) -> CodeEntry:
        stand_in = text.startswith(STAND_IN_PREFIX)
        body = text[len(STAND_IN_PREFIX) :] if stand_in else text
        reference, _, digest = body.rpartition(" ")
        if not digest.startswith(_DIGEST) or not reference:
            return cls(body, "", stand_in)
        return cls(reference, digest[len(_DIGEST) :], stand_in)


@dataclass(frozen=True, slots=True)
class CodeManifest:
    #: Per catalog behavior, in catalog order.
    entries: Mapping[str, CodeEntry]
    #: module name -> source text, for the developer's modules (not aeroexec's).
    sources: Mapping[str, str]

    def metadata(self) -> dict[str, str]:
        return {name: entry.text() for name, entry in self.entries.items()}

    def attachments(self) -> dict[str, str]:
        return {f"{ATTACHMENT_PREFIX}{module}.py": text for module, text in self.sources.items()}

    @property
    def stand_ins(self) -> tuple[str, ...]:
        return tuple(name for name, entry in self.entries.items() if entry.stand_in)


def _module_source(module_name: str) -> str | None:
    module = sys.modules.get(module_name)
    loader = getattr(module, "__loader__", None)
    get_source = getattr(loader, "get_source", None)
    if get_source is None:
        return None
    try:
        source = get_source(module_name)
    except (ImportError, OSError):
        return None
    return source if isinstance(source, str) else None


def _hierarchy_modules(cls: type) -> Iterator[str]:
    seen: set[str] = set()
    for klass in cls.__mro__:
        if klass is object or klass.__module__ in seen:
            continue
        seen.add(klass.__module__)
        yield klass.__module__


def _is_aeroexec(module_name: str) -> bool:
    return module_name == "aeroexec" or module_name.startswith("aeroexec.")


def _entry(implementation: Implementation, sources: dict[str, str]) -> CodeEntry:
    digest = hashlib.sha256()
    digest.update(f"{implementation.reference}\n".encode())
    for module_name in _hierarchy_modules(implementation.cls):
        source = _module_source(module_name)
        digest.update(f"{module_name}\n".encode())
        digest.update((source if source is not None else "(source unavailable)").encode())
        digest.update(b"\0")
        if source is not None and not _is_aeroexec(module_name):
            sources.setdefault(module_name, source)
    return CodeEntry(
        implementation.reference, digest.hexdigest()[:_DIGITS], implementation.stand_in
    )


def code_manifest(behaviors: BehaviorSet, catalog: Catalog) -> CodeManifest:
    """The manifest of the code that implements `catalog`'s behaviors (those without an
    implementation are left out: a session refuses to run them)."""
    sources: dict[str, str] = {}
    entries = {
        name: _entry(behaviors.implementations[name], sources)
        for name in catalog.behaviors
        if name in behaviors.implementations
    }
    return CodeManifest(entries, dict(sorted(sources.items())))


def code_changes(recorded: Mapping[str, str], current: Mapping[str, str]) -> tuple[str, ...]:
    """One line per behavior the recording names whose code is not the code now: its
    class changed, its source changed, a stand-in came or went. Behaviors the current
    catalog does not have are not code changes (the catalog changed)."""
    lines: list[str] = []
    for name, text in recorded.items():
        now_text = current.get(name)
        if now_text is None:
            continue
        was, now = CodeEntry.parse(text), CodeEntry.parse(now_text)
        if was == now:
            continue
        if was.stand_in and not now.stand_in:
            lines.append(f"{name}: implemented by {now.reference} (was a stand-in)")
        elif now.stand_in and not was.stand_in:
            lines.append(f"{name}: a stand-in now (was {was.reference})")
        elif was.reference != now.reference:
            lines.append(f"{name}: {was.reference} -> {now.reference}")
        else:
            lines.append(
                f"{name}: {now.reference} source changed ({_DIGEST}{was.digest} -> {now.digest})"
            )
    return tuple(lines)
