"""Find the behaviors a command runs with, from every source, in order.

1. `--behaviors MODULE_OR_FILE` on the command line (repeatable);
2. `behaviors = [...]` in the project configuration (`[tool.aeroexec]` / aeroexec.toml);
3. installed packages' entry points in the group `aeroexec.behaviors`;
4. aeroexec's standard library, last.

A behavior from the first three sources replaces the standard library's behavior of the
same name; two of them implementing the same name is an error naming both (nothing
decides silently which one flies). What a module provides: the `Behavior` subclasses in
its namespace with a `name` (only those in `__all__` when it has one), leaving out
aeroexec's own classes that it merely imported; a package without `__all__` also provides
those of its public submodules (imported in name order). An entry point names a module
or one `Behavior` subclass.

`discover(sources)` does it; `BehaviorSources` says where to look and is plain data, so
a replay worker process can discover the same set again.
"""

from __future__ import annotations

import inspect
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

from aeroexec.catalog.model import Catalog
from aeroexec.config import key_mark
from aeroexec.display import shown
from aeroexec.errors import BehaviorError, Mark
from aeroexec.executive.behavior import Behavior, GenericBehavior
from aeroexec.plugins.loading import Importer, Named, class_mark, failure_in_user_code

ENTRY_POINT_GROUP = "aeroexec.behaviors"
STANDARD = "standard library"
COMMAND_LINE = "--behaviors"
#: What an implementation that only stands in for a missing one is recorded as.
STAND_IN = GenericBehavior

#: The hooks that make a class look like a behavior (to catch one that forgot the base).
_HOOKS = ("check_situation", "on_start", "on_run", "on_stop")


@dataclass(frozen=True, slots=True)
class BehaviorSources:
    """Where to look for behaviors (plain data: a replay worker discovers again)."""

    #: `--behaviors` values, relative to `command_line_root`.
    command_line: tuple[str, ...] = ()
    command_line_root: str = "."
    #: The configuration's `behaviors` (None when it has no such key), relative to its
    #: directory, and the file itself.
    config: tuple[str, ...] | None = None
    config_file: str | None = None
    config_label: str = ""
    entry_points: bool = True


@dataclass(frozen=True, slots=True)
class Implementation:
    """One behavior class and where it came from."""

    name: str
    cls: type[Behavior]
    #: Which source: "--behaviors", the configuration's label, "entry point", "standard library".
    source: str
    #: What that source named: the module or file, or the entry point.
    origin: str
    #: True when it replaces the standard library's implementation of the same name.
    overrides: bool = False

    @property
    def reference(self) -> str:
        """`module:Class`, as entry points and pytest spell an object."""
        return f"{self.cls.__module__}:{self.cls.__qualname__}"

    @property
    def mark(self) -> Mark:
        return class_mark(self.cls)

    @property
    def standard(self) -> bool:
        return self.source == STANDARD

    @property
    def stand_in(self) -> bool:
        return self.cls is STAND_IN


@dataclass(frozen=True)
class BehaviorSet:
    """Every implementation found, by behavior name, and where the search looked."""

    implementations: Mapping[str, Implementation]
    #: Where behaviors were looked for, in order (for messages).
    searched: tuple[str, ...] = ()
    #: True when the project said what its behaviors are: `--behaviors`, a configuration
    #: `behaviors` key (even an empty list) or an installed entry point. The verifier
    #: checks a catalog against code only then.
    declared: bool = False
    #: Catalog behaviors that were deliberately given stand-ins (`with_stand_ins`).
    stand_ins: tuple[str, ...] = field(default=())

    def library(self) -> dict[str, type[Behavior]]:
        return {name: impl.cls for name, impl in self.implementations.items()}

    def missing(self, catalog: Catalog) -> tuple[str, ...]:
        """Catalog behaviors without an implementation, in catalog order."""
        return tuple(name for name in catalog.behaviors if name not in self.implementations)

    def for_catalog(self, catalog: Catalog, allow_unimplemented: bool = False) -> BehaviorSet:
        """The set for running `catalog`: complete, or a `BehaviorError` listing what is
        missing and where it was looked for. With `allow_unimplemented`, each missing
        behavior gets an explicit stand-in (listed in `stand_ins`)."""
        missing = self.missing(catalog)
        if not missing:
            return self
        if not allow_unimplemented:
            first = catalog.behaviors[missing[0]].mark
            raise BehaviorError(
                f"no implementation for {', '.join(missing)} (looked in: "
                f"{'; '.join(self.searched)}); give --allow-unimplemented to run "
                "stand-ins that succeed after 1 s",
                first if first.file and first.file != "<memory>" else None,
            )
        return self.with_stand_ins(missing)

    def with_stand_ins(self, names: Iterable[str]) -> BehaviorSet:
        names = tuple(names)
        implementations = dict(self.implementations)
        for name in names:
            implementations[name] = Implementation(name, STAND_IN, "stand-in", "")
        return BehaviorSet(implementations, self.searched, self.declared, (*self.stand_ins, *names))

    def user(self) -> tuple[Implementation, ...]:
        """The implementations that are not aeroexec's own (nor stand-ins)."""
        return tuple(i for i in self.implementations.values() if not i.standard and not i.stand_in)


# -- the standard library ------------------------------------------------------------------
def _standard() -> dict[str, Implementation]:
    from aeroexec.behaviors import STANDARD_LIBRARY

    return {
        name: Implementation(name, cls, STANDARD, "aeroexec.behaviors")
        for name, cls in STANDARD_LIBRARY.items()
    }


def standard_set() -> BehaviorSet:
    """Just aeroexec's standard library (what a session uses when given no set)."""
    return BehaviorSet(_standard(), (STANDARD,))


# -- discovery ---------------------------------------------------------------------------
class _Collector:
    def __init__(self) -> None:
        self.found: dict[str, Implementation] = {}
        self.searched: list[str] = []

    def add(self, cls: type[Behavior], source: str, origin: str) -> None:
        previous = self.found.get(cls.name)
        if previous is not None:
            if previous.cls is cls:
                return
            raise BehaviorError(
                f"behavior {cls.name} is implemented twice: {_describe(cls, source, origin)} "
                f"and {_describe(previous.cls, previous.source, previous.origin)}; "
                "keep one (or list the one you mean in the module's __all__)",
                class_mark(cls),
            )
        self.found[cls.name] = Implementation(cls.name, cls, source, origin)


def _describe(cls: type, source: str, origin: str) -> str:
    mark = class_mark(cls)
    where = f"{mark.file}:{mark.line}" if mark.line else mark.file
    return f"{cls.__module__}:{cls.__qualname__} ({where}, from {source} {origin})"


def discover(sources: BehaviorSources) -> BehaviorSet:
    """Every behavior the sources provide, then the standard library for the rest.
    `BehaviorError` (one line, naming the file) for anything that cannot be used."""
    importer = Importer()
    collector = _Collector()
    declared = bool(sources.command_line) or sources.config is not None
    root = Path(sources.command_line_root)
    for spec in sources.command_line:
        named = Named(f"{COMMAND_LINE} {spec}")
        for cls in behaviors_in(importer.load(spec, root, named), importer, named):
            collector.add(cls, COMMAND_LINE, spec)
    if sources.command_line:
        collector.searched.append(f"{COMMAND_LINE} {', '.join(sources.command_line)}")
    if sources.config is not None and sources.config_file is not None:
        config_file = Path(sources.config_file)
        named_at = key_mark(config_file, "behaviors")
        for spec in sources.config:
            named = Named(f"behaviors entry '{spec}'", named_at)
            module = importer.load(spec, config_file.parent, named)
            for cls in behaviors_in(module, importer, named):
                collector.add(cls, shown(config_file), spec)
        listed = ", ".join(sources.config) if sources.config else "none"
        collector.searched.append(f"{sources.config_label} behaviors ({listed})")
    if sources.entry_points:
        count = _entry_points(collector)
        declared = declared or count > 0
        collector.searched.append(
            f"entry points '{ENTRY_POINT_GROUP}' ({count} installed)"
            if count
            else f"entry points '{ENTRY_POINT_GROUP}' (none installed)"
        )
    implementations = dict(collector.found)
    for name, standard in _standard().items():
        if name in implementations:
            user = implementations[name]
            implementations[name] = Implementation(
                name, user.cls, user.source, user.origin, overrides=True
            )
        else:
            implementations[name] = standard
    collector.searched.append(f"the {STANDARD}")
    found = BehaviorSet(implementations, tuple(collector.searched), declared)
    _found[sources] = found
    return found


def behaviors_in(
    module: ModuleType, importer: Importer | None = None, named: Named | None = None
) -> list[type[Behavior]]:
    """The behaviors a module provides (see the module docstring): a package without
    `__all__` provides those of its public submodules too. `BehaviorError` for a module
    that provides none, or a class that has behavior hooks but is no Behavior."""
    found = _in_namespace(module)
    explicit = getattr(module, "__all__", None) is not None
    if hasattr(module, "__path__") and not explicit:
        importer = importer or Importer()
        for submodule in importer.submodules(module, named or Named(module.__name__)):
            found.extend(_in_namespace(submodule))
    if not found:
        raise BehaviorError(
            f"{module.__name__} provides no behavior (a subclass of "
            "aeroexec.executive.Behavior with a `name`)",
            _module_mark(module),
        )
    return sorted(dict.fromkeys(found), key=lambda c: (c.name, c.__module__, c.__qualname__))


def _in_namespace(module: ModuleType) -> list[type[Behavior]]:
    names = getattr(module, "__all__", None)
    explicit = names is not None
    candidates = (
        [(n, getattr(module, n, None)) for n in names] if explicit else list(vars(module).items())
    )
    found: list[type[Behavior]] = []
    for attribute, value in candidates:
        if not inspect.isclass(value):
            if explicit:
                raise BehaviorError(
                    f"{attribute} is in __all__ but is not a Behavior subclass",
                    _module_mark(module),
                )
            continue
        if issubclass(value, Behavior):
            if not explicit and _aeroexec_own(value):
                continue  # imported to subclass or to use, not offered
            if not isinstance(value.name, str) or not value.name:
                if explicit:
                    raise BehaviorError(
                        f"{value.__qualname__} is in __all__ but has no behavior `name`",
                        class_mark(value),
                    )
                continue
            found.append(value)
        elif (explicit or value.__module__ == module.__name__) and _looks_like_a_behavior(value):
            raise BehaviorError(
                f"{value.__qualname__} has behavior hooks but is not a subclass of "
                "aeroexec.executive.Behavior",
                class_mark(value),
            )
        elif explicit:
            raise BehaviorError(
                f"{attribute} is in __all__ but is not a Behavior subclass", _module_mark(module)
            )
    return found


def _aeroexec_own(cls: type) -> bool:
    return cls.__module__ == "aeroexec" or cls.__module__.startswith("aeroexec.")


def _looks_like_a_behavior(cls: type) -> bool:
    return isinstance(getattr(cls, "name", None), str) and any(h in vars(cls) for h in _HOOKS)


def _module_mark(module: ModuleType) -> Mark:
    file = getattr(module, "__file__", None)
    return Mark(shown(file)) if file else Mark(module.__name__)


def _entry_points(collector: _Collector) -> int:
    from importlib.metadata import entry_points

    points = sorted(
        entry_points(group=ENTRY_POINT_GROUP),
        key=lambda ep: (getattr(ep.dist, "name", "") or "", ep.name, ep.value),
    )
    for point in points:
        dist = point.dist
        label = f"{point.name} = {point.value}" + (
            f" ({dist.name} {dist.version})" if dist is not None else ""
        )
        where = Mark(f"entry point {label}")
        try:
            loaded = point.load()
        except SyntaxError as exc:
            mark = Mark(shown(exc.filename or where.file), exc.lineno or 0, exc.offset or 0)
            raise BehaviorError(f"invalid Python: {exc.msg}", mark) from None
        except Exception as exc:
            raise failure_in_user_code(exc, f"loading entry point {label} failed", where) from None
        if isinstance(loaded, ModuleType):
            classes = behaviors_in(loaded)
        elif inspect.isclass(loaded) and issubclass(loaded, Behavior) and loaded.name:
            classes = [loaded]
        else:
            what = type(loaded).__name__ if not inspect.isclass(loaded) else loaded.__qualname__
            raise BehaviorError(
                f"entry point {label} names {what}, not a module or a Behavior subclass", where
            )
        for cls in classes:
            collector.add(cls, "entry point", label)
    return len(points)


#: The last set discovered for each sources value, in this process.
_found: dict[BehaviorSources, BehaviorSet] = {}


def discovered(sources: BehaviorSources) -> BehaviorSet:
    """What `discover(sources)` last found in this process, discovering only the first
    time: a replay batch (and each worker process) imports the behaviors once."""
    found = _found.get(sources)
    return found if found is not None else discover(sources)


__all__ = [
    "ENTRY_POINT_GROUP",
    "BehaviorSet",
    "BehaviorSources",
    "Implementation",
    "behaviors_in",
    "discover",
    "discovered",
    "standard_set",
]
