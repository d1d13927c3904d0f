"""Find the behaviors a command runs with, from every source, in order.

1. `--behaviors MODULE_OR_FILE` on the command line (repeatable);
2. `behaviors = [...]` in the project configuration (`[tool.aeroexec]` / aeroexec.toml);
3. installed packages' entry points in the group `aeroexec.behaviors` (the plugins);
4. aeroexec's standard library, last.

The order is a precedence between levels: the project's own behaviors (1 and 2) replace
an installed plugin's of the same name, and both replace the standard library's. The
replaced plugin is still imported (which behaviors it has is only known then); its class
of that name does not run, and the command says so in a note (`BehaviorSet.notes`).
Within one level two implementations of one name are an error naming both: `--behaviors`
and the configuration are both the project's own, and two installed plugins have no order
between them, so nothing decides silently which one flies.

Plugins load automatically, as pytest's do, and can be turned off the same two ways:
all of them with the environment variable `AEROEXEC_DISABLE_PLUGIN_AUTOLOAD=1` (a
project can still name a plugin's module with `--behaviors`), or one distribution with
`--disable-plugin NAME` / the configuration's `disable_plugins`. A disabled plugin is
never imported. One that fails to import is an error, not a warning, even when the
mission may not use it: which behaviors it provides is only known once it has imported,
so it may have been the code meant to replace a standard behavior, and flying the
standard one instead (or recording it as what ran) would be the surprise this module
exists to prevent. The error names the distribution and how to turn it off.

What a module provides: the `Behavior` subclasses in
its namespace with a `name` (only those in `__all__` when it has one), leaving out
aeroexec's own classes that it merely imported; a package without `__all__` also provides
those of its public submodules (imported in name order). An entry point names a module
or one `Behavior` subclass.

`discover(sources)` does it; `BehaviorSources` says where to look and is plain data, so
a replay worker process can discover the same set again.
"""

from __future__ import annotations

import inspect
import os
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

from aeroexec.catalog.model import Catalog
from aeroexec.config import key_mark
from aeroexec.display import shown
from aeroexec.errors import BehaviorError, Mark
from aeroexec.executive.behavior import Behavior, GenericBehavior
from aeroexec.plugins.loading import Importer, Named, class_mark, failure_in_user_code

if TYPE_CHECKING:
    from importlib.metadata import EntryPoint

ENTRY_POINT_GROUP = "aeroexec.behaviors"
#: Set (to anything but "" or "0") to load no plugin automatically, as pytest's
#: PYTEST_DISABLE_PLUGIN_AUTOLOAD.
DISABLE_AUTOLOAD = "AEROEXEC_DISABLE_PLUGIN_AUTOLOAD"
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
    #: Load installed plugins (entry points) at all (`autoload_enabled()`), and when not,
    #: why not (for messages: "AEROEXEC_DISABLE_PLUGIN_AUTOLOAD is set").
    entry_points: bool = True
    entry_points_off: str = ""
    #: Installed plugins not to load: distribution names (or entry point names).
    disabled_plugins: tuple[str, ...] = ()


def autoload_enabled(environ: Mapping[str, str] | None = None) -> bool:
    """False when `AEROEXEC_DISABLE_PLUGIN_AUTOLOAD` is set to anything but "" or "0"."""
    value = (os.environ if environ is None else environ).get(DISABLE_AUTOLOAD, "")
    return value.strip() in ("", "0")


def plugin_key(name: str) -> str:
    """A distribution name as pip compares them (PEP 503): `Drone_Tricks` is `drone-tricks`."""
    return re.sub(r"[-_.]+", "-", name).lower()


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
    #: The installed plugin's implementation it replaces (the project's own only).
    shadows: Implementation | None = None

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

    def notes(self) -> tuple[str, ...]:
        """What a command says on stderr: each installed plugin's behavior that the
        project's own replaces."""
        return tuple(
            f"{i.name}: {_describe(i.cls, i.source, i.origin)} replaces the installed "
            f"plugin's {i.shadows.reference} (from {i.shadows.origin})"
            for i in self.implementations.values()
            if i.shadows is not None
        )

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
    """One level of the order: two implementations of one name in it are an error."""

    def __init__(
        self, remedy: str = "keep one (or list the one you mean in the module's __all__)"
    ) -> None:
        self.found: dict[str, Implementation] = {}
        self.searched: list[str] = []
        self.remedy = remedy

    def add(self, cls: type[Behavior], source: str, origin: str) -> None:
        previous = self.found.get(cls.name)
        if previous is not None:
            if previous.cls is cls:
                return
            raise BehaviorError(
                f"behavior {cls.name} is implemented twice: {_describe(cls, source, origin)} "
                f"and {_describe(previous.cls, previous.source, previous.origin)}; "
                f"{self.remedy}",
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
    implementations = dict(collector.found)
    if sources.entry_points:
        installed = _Collector(
            "two installed plugins have no order between them: turn one off with "
            "--disable-plugin NAME"
        )
        count, disabled = _entry_points(installed, sources.disabled_plugins)
        declared = declared or count > disabled
        for name, plugin in installed.found.items():
            own = implementations.get(name)
            if own is None:
                implementations[name] = plugin
            else:
                implementations[name] = Implementation(
                    name, own.cls, own.source, own.origin, shadows=plugin
                )
        off = f", {disabled} turned off" if disabled else ""
        collector.searched.append(
            f"entry points '{ENTRY_POINT_GROUP}' ({count} installed{off})"
            if count or disabled
            else f"entry points '{ENTRY_POINT_GROUP}' (none installed)"
        )
    elif sources.entry_points_off:
        collector.searched.append(
            f"entry points '{ENTRY_POINT_GROUP}' (not loaded: {sources.entry_points_off})"
        )
    for name, standard in _standard().items():
        if name in implementations:
            user = implementations[name]
            implementations[name] = Implementation(
                name, user.cls, user.source, user.origin, overrides=True, shadows=user.shadows
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


def _entry_points(collector: _Collector, disabled: Iterable[str]) -> tuple[int, int]:
    """Load every installed plugin's entry points into `collector`, but those of the
    `disabled` distributions (or entry point names): (how many are installed, how many
    of them were turned off)."""
    from importlib.metadata import entry_points

    off = {plugin_key(name) for name in disabled}
    points = sorted(
        entry_points(group=ENTRY_POINT_GROUP),
        key=lambda ep: (getattr(ep.dist, "name", "") or "", ep.name, ep.value),
    )
    loaded = 0
    for point in points:
        plugin = _Plugin(point)
        if plugin.key in off or plugin_key(point.name) in off:
            continue
        loaded += 1
        for cls in plugin.behaviors():
            collector.add(cls, "entry point", plugin.label)
    return len(points), len(points) - loaded


class _Plugin:
    """One installed entry point, and how its errors name it: by its distribution, once,
    with how to turn it off."""

    def __init__(self, point: EntryPoint) -> None:
        self.point = point
        dist = point.dist
        self.name = dist.name if dist is not None else point.name
        self.key = plugin_key(self.name)
        self.label = f"{point.name} = {point.value}" + (
            f" ({dist.name} {dist.version})" if dist is not None else ""
        )
        version = f" {dist.version}" if dist is not None else ""
        self.what = (
            f"installed plugin {self.name}{version} (entry point {point.name} = {point.value})"
        )

    def behaviors(self) -> list[type[Behavior]]:
        try:
            return self._behaviors()
        except BehaviorError as exc:
            named = exc.message.startswith(self.what)
            message = exc.message if named else f"{self.what}: {exc.message}"
            raise BehaviorError(f"{message}; {self.remedy}", exc.mark) from None

    @property
    def remedy(self) -> str:
        return (
            f"turn it off with --disable-plugin {self.name} (or every installed plugin with "
            f"{DISABLE_AUTOLOAD}=1)"
        )

    def _behaviors(self) -> list[type[Behavior]]:
        declared_at = self._declared_at()
        try:
            loaded = self.point.load()
        except SyntaxError as exc:
            mark = (
                Mark(shown(exc.filename), exc.lineno or 0, exc.offset or 0)
                if exc.filename
                else declared_at
            )
            raise BehaviorError(f"{self.what} is not valid Python: {exc.msg}", mark) from None
        except Exception as exc:
            raise failure_in_user_code(exc, f"{self.what} failed to load", declared_at) from None
        if isinstance(loaded, ModuleType):
            return behaviors_in(loaded)
        if inspect.isclass(loaded) and issubclass(loaded, Behavior) and loaded.name:
            return [loaded]
        what = type(loaded).__name__ if not inspect.isclass(loaded) else loaded.__qualname__
        raise BehaviorError(
            f"{self.what} names {what}, not a module or a Behavior subclass", declared_at
        )

    def _declared_at(self) -> Mark | None:
        """The line of the distribution's entry_points.txt that declares it, when the
        distribution is a directory on disk (a wheel's .dist-info, an egg-info)."""
        where = getattr(self.point.dist, "_path", None)  # PathDistribution's directory
        if not isinstance(where, Path):
            return None
        path = where / "entry_points.txt"
        try:
            lines = path.read_text(encoding="utf-8").splitlines()
        except (OSError, UnicodeDecodeError):
            return None
        group = ""
        for number, line in enumerate(lines, 1):
            text = line.strip()
            if text.startswith("["):
                group = text.strip("[]").strip()
            elif group == ENTRY_POINT_GROUP and text.partition("=")[0].strip() == self.point.name:
                return Mark(shown(path), number, line.index(text) + 1)
        return Mark(shown(path))


#: The last set discovered for each sources value, in this process.
_found: dict[BehaviorSources, BehaviorSet] = {}


def discovered(sources: BehaviorSources) -> BehaviorSet:
    """What `discover(sources)` last found in this process, discovering only the first
    time: a replay batch (and each worker process) imports the behaviors once."""
    found = _found.get(sources)
    return found if found is not None else discover(sources)


__all__ = [
    "DISABLE_AUTOLOAD",
    "ENTRY_POINT_GROUP",
    "BehaviorSet",
    "BehaviorSources",
    "Implementation",
    "autoload_enabled",
    "behaviors_in",
    "discover",
    "discovered",
    "plugin_key",
    "standard_set",
]
