"""Import what a developer named as behaviors: a module, a package, a file.

Importing a module the user named *is* running code the user asked to run; nothing here
imports a name read from a recording or a catalog. Every failure becomes one
`BehaviorError` naming the file and line it is about: a syntax error at its place, an
import error or any other exception at the deepest line of the developer's own code in
the traceback, a module that does not exist at the configuration line that named it.

Names resolve as pytest's "prepend" import mode does: a file (or a package directory)
is imported under its package-qualified name with the first directory above its
packages put on `sys.path`, so its own absolute imports work; a module name is looked
for first under the directory it is relative to (the working directory for
`--behaviors`, the configuration file's directory for the configuration), then among the
installed packages. A module loaded from a project directory is imported afresh the
first time a discovery asks for it, so an edited file is never served from an older
import in the same process.
"""

from __future__ import annotations

import importlib
import inspect
import os
import pkgutil
import sys
import traceback
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType, TracebackType

from aeroexec.display import shown
from aeroexec.errors import BehaviorError, Mark
from aeroexec.interrupts import TimedOut, deadline, user_code


@dataclass(frozen=True, slots=True)
class Named:
    """How the user named a behavior module: `label` for messages ("--behaviors x",
    "behaviors entry 'x'"), `at` the configuration line (None on the command line)."""

    label: str
    at: Mark | None = None

    def error(self, problem: str) -> BehaviorError:
        return BehaviorError(f"{self.label}: {problem}", self.at)


class Importer:
    """Imports for one discovery: each project package is imported afresh once."""

    def __init__(self) -> None:
        self._fresh: set[str] = set()

    def load(self, spec: str, root: Path, named: Named) -> ModuleType:
        """Import `spec` (a module name, a `.py` file or a package directory; relative
        ones against `root`). `named`: how and where the user named it, for errors that
        have no file of their own (a module that does not exist)."""
        if _looks_like_path(spec) or (root / spec).exists():
            path = Path(spec).expanduser()
            path = path if path.is_absolute() else root / path
            base, dotted = _package_name(path, named)
            return self._import(dotted, base, named)
        if _local_module(spec, root) is not None:
            return self._import(spec, root, named)
        return self._import(spec, None, named, looked_in=root)

    def _import(
        self, dotted: str, base: Path | None, named: Named, looked_in: Path | None = None
    ) -> ModuleType:
        importlib.invalidate_caches()
        if base is not None:
            base_text = str(base)
            if base_text not in sys.path:
                sys.path.insert(0, base_text)
            top = dotted.split(".", 1)[0]
            if top not in self._fresh:
                self._fresh.add(top)
                _forget(top)
        return import_module(dotted, named, base or looked_in or Path.cwd())

    def submodules(self, package: ModuleType, named: Named) -> Iterator[ModuleType]:
        """A package's public submodules (no leading underscore), depth first, in name
        order, imported with the same error reporting."""
        for info in sorted(pkgutil.iter_modules(package.__path__), key=lambda i: i.name):
            if info.name.startswith("_"):
                continue
            module = import_module(f"{package.__name__}.{info.name}", named, None)
            yield module
            if info.ispkg:
                yield from self.submodules(module, named)


def import_module(dotted: str, named: Named, looked_in: Path | None) -> ModuleType:
    """`importlib.import_module`, with every failure a `BehaviorError` at its place.

    Importing runs the module's top level, the user's code: a signal stops it wherever
    it is, and so does `--timeout` (`interrupts.user_code`). A module that calls
    `sys.exit()` fails to import; it does not end aeroexec."""
    try:
        with user_code(deadline()):
            return importlib.import_module(dotted)
    except TimedOut as exc:
        raise failure_in_user_code(
            exc, f"importing {named.label} failed", named.at, described=str(exc)
        ) from None
    except SystemExit as exc:
        raise failure_in_user_code(
            exc, f"importing {named.label} failed", named.at, described=f"sys.exit({exc.code!r})"
        ) from None
    except SyntaxError as exc:
        raise _syntax_error(exc, named) from None
    except ModuleNotFoundError as exc:
        if exc.name is not None and (dotted == exc.name or dotted.startswith(exc.name + ".")):
            where = shown(looked_in or Path.cwd())
            raise named.error(
                f"no module named '{exc.name}' (looked in {where} and among the installed packages)"
            ) from None
        raise failure_in_user_code(exc, f"importing {named.label} failed", named.at) from None
    except Exception as exc:
        raise failure_in_user_code(exc, f"importing {named.label} failed", named.at) from None


def _looks_like_path(spec: str) -> bool:
    return spec.endswith(".py") or "/" in spec or os.sep in spec or spec.startswith(".")


def _local_module(dotted: str, root: Path) -> Path | None:
    parts = dotted.split(".")
    if not all(part.isidentifier() for part in parts):
        return None
    candidate = root.joinpath(*parts)
    for path in (candidate.with_suffix(".py"), candidate / "__init__.py"):
        if path.is_file():
            return path
    return None


def _package_name(path: Path, named: Named) -> tuple[Path, str]:
    """(the directory to put on sys.path, the dotted name) for a file or package."""
    path = path.resolve()
    if path.is_dir():
        if not (path / "__init__.py").is_file():
            raise named.error(
                f"{shown(path)} is a directory without __init__.py (name a package or a .py file)"
            )
        parts = [path.name]
        directory = path.parent
    elif path.is_file():
        if path.suffix != ".py":
            raise BehaviorError("not a .py file (behaviors are Python)", Mark(shown(path)))
        parts = [] if path.name == "__init__.py" else [path.stem]
        directory = path.parent
        if not parts:
            parts = [directory.name]
            directory = directory.parent
    else:
        raise named.error(f"no such file or directory: {shown(path)}")
    while (directory / "__init__.py").is_file():
        parts.insert(0, directory.name)
        directory = directory.parent
    if not all(part.isidentifier() for part in parts):
        raise BehaviorError(
            f"{'.'.join(parts)} is not an importable module name", Mark(shown(path))
        )
    return directory, ".".join(parts)


def _forget(top: str) -> None:
    for name in [n for n in sys.modules if n == top or n.startswith(top + ".")]:
        del sys.modules[name]


def _syntax_error(exc: SyntaxError, named: Named) -> BehaviorError:
    if not exc.filename:
        return named.error(f"invalid Python: {exc.msg}")
    mark = Mark(shown(exc.filename), exc.lineno or 0, exc.offset or 0)
    return BehaviorError(f"invalid Python: {exc.msg}", mark)


def _frames(tb: TracebackType | None) -> Iterator[traceback.FrameSummary]:
    yield from traceback.extract_tb(tb)


def _is_ours(filename: str) -> bool:
    """Frames of Python's import machinery and of aeroexec itself are not the
    developer's code."""
    if filename.startswith("<"):
        return True
    package = str(Path(__file__).resolve().parent.parent)
    return filename.startswith(package) or "importlib" in Path(filename).parts


def failure_in_user_code(
    exc: BaseException, what: str, fallback: Mark | None, described: str = ""
) -> BehaviorError:
    """`what`: TypeName: message (or `described`), at the deepest frame of the
    developer's own code."""
    mark = fallback
    for frame in _frames(exc.__traceback__):
        if not _is_ours(frame.filename):
            mark = Mark(shown(frame.filename), frame.lineno or 0, 1 if frame.lineno else 0)
    return BehaviorError(f"{what}: {described or f'{type(exc).__name__}: {exc}'}", mark)


def class_mark(cls: type) -> Mark:
    """Where a class is defined (file:line), as well as Python can tell."""
    try:
        file = inspect.getsourcefile(cls) or inspect.getfile(cls)
    except (TypeError, OSError):
        return Mark(f"{cls.__module__}:{cls.__qualname__}")
    try:
        _, line = inspect.getsourcelines(cls)
    except (OSError, TypeError):
        line = 0
    return Mark(shown(file), line, 1 if line else 0)
