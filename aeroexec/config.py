"""The project configuration: `[tool.aeroexec]` in `pyproject.toml`, or `aeroexec.toml`.

Found as ruff and pytest find theirs: from the working directory upward, the first
directory holding an `aeroexec.toml` (keys at the top level) or a `pyproject.toml` with a
`[tool.aeroexec]` table; a `pyproject.toml` without that table is passed over. Relative
paths resolve against the directory of the file that names them, so a command gives the
same answer from any subdirectory of the project.

    [tool.aeroexec]
    behaviors = ["mybehaviors", "tools/survey.py"]   # modules or files (run, fly, replay, verify)
    catalog = "catalog.yaml"                          # run, fly, verify, behaviors
    world = "worlds/field.yaml"                        # run
    seed = 7                                           # run
    connect = "udpin:127.0.0.1:14551"                  # fly
    disable_plugins = ["dronetricks"]                  # installed plugins not to load

    [tool.aeroexec.verify]                             # verify, as ruff's [tool.ruff.lint]
    catalogs = ["catalog/*.yaml"]                      # what a bare `aeroexec verify` checks
    missions = ["missions/*.py"]
    select = ["AX"]                                    # codes or prefixes
    extend-select = []
    ignore = ["AX708"]
    per-file-ignores = {"missions/legacy_*.py" = ["AX7"]}

An option on the command line wins over the file; the file wins over aeroexec's own
defaults. A malformed file is a `ConfigError` naming the file and line.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from aeroexec.display import shown
from aeroexec.errors import ConfigError, Mark

PYPROJECT = "pyproject.toml"
AEROEXEC_TOML = "aeroexec.toml"
TABLE = "tool.aeroexec"


@dataclass(frozen=True, slots=True)
class ProjectConfig:
    """What a project pins. `None` means the file does not say (or there is no file)."""

    #: The file it was read from; None when no configuration was found.
    path: Path | None = None
    #: Behavior modules or files, in order; None when the key is absent. An empty list
    #: is a statement too: the project's behaviors are the standard library's.
    behaviors: tuple[str, ...] | None = None
    catalog: Path | None = None
    world: Path | None = None
    seed: int | None = None
    connect: str | None = None
    #: Installed plugins (distribution names) whose entry points are not loaded.
    disable_plugins: tuple[str, ...] | None = None
    verify: VerifyConfig | None = None

    @property
    def root(self) -> Path:
        """The directory relative names resolve against (the working directory if none)."""
        return self.path.parent if self.path is not None else Path.cwd()

    @property
    def label(self) -> str:
        """How messages name it: `pyproject.toml [tool.aeroexec]` or `aeroexec.toml`."""
        if self.path is None:
            return "(no project configuration)"
        table = f" [{TABLE}]" if self.path.name == PYPROJECT else ""
        return f"{shown(self.path)}{table}"


NO_CONFIG = ProjectConfig()


@dataclass(frozen=True, slots=True)
class VerifyConfig:
    """`[tool.aeroexec.verify]`: what `aeroexec verify` checks and reports."""

    #: Catalog paths or glob patterns, resolved against the configuration's directory.
    catalogs: tuple[str, ...] = ()
    missions: tuple[str, ...] = ()
    select: tuple[str, ...] | None = None
    extend_select: tuple[str, ...] = ()
    ignore: tuple[str, ...] = ()
    #: glob pattern (relative to the configuration's directory) -> codes or prefixes.
    per_file_ignores: tuple[tuple[str, tuple[str, ...]], ...] = ()


NO_VERIFY = VerifyConfig()


def find_config(start: str | Path | None = None) -> tuple[Path, dict[str, Any]] | None:
    """The nearest configuration file from `start` (default: the working directory)
    upward, with its aeroexec table; None when there is none."""
    here = Path(start) if start is not None else Path.cwd()
    here = here.resolve()
    for directory in (here, *here.parents):
        candidate = directory / AEROEXEC_TOML
        if candidate.is_file():
            return candidate, _read(candidate)
        candidate = directory / PYPROJECT
        if candidate.is_file():
            table = _aeroexec_table(candidate, _read(candidate))
            if table is not None:
                return candidate, table
    return None


def load_config(start: str | Path | None = None) -> ProjectConfig:
    """The project configuration found from `start` upward (`NO_CONFIG` if none)."""
    found = find_config(start)
    if found is None:
        return NO_CONFIG
    path, table = found
    return _parse(path, table)


# -- reading -----------------------------------------------------------------------------
_POSITION = re.compile(r"\s*\(at line (\d+), column (\d+)\)\s*$")


def _read(path: Path) -> dict[str, Any]:
    # Imported here: most commands run where no configuration file exists.
    import tomllib

    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"not UTF-8 text (byte {exc.start})", Mark(shown(path))) from None
    except OSError as exc:
        raise ConfigError(f"cannot read: {exc.strerror or exc}", Mark(shown(path))) from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        message = str(exc)
        line = getattr(exc, "lineno", None)
        column = getattr(exc, "colno", None)
        found = _POSITION.search(message)
        if found is not None:
            message = message[: found.start()]
            line, column = int(found[1]), int(found[2])
        mark = Mark(shown(path), line or 0, column or 0)
        raise ConfigError(f"invalid TOML: {message}", mark) from None


def _aeroexec_table(path: Path, document: dict[str, Any]) -> dict[str, Any] | None:
    tool = document.get("tool")
    if not isinstance(tool, dict) or "aeroexec" not in tool:
        return None
    table = tool["aeroexec"]
    if not isinstance(table, dict):
        raise ConfigError(f"[{TABLE}] must be a table", key_mark(path, None))
    return table


# -- checking ----------------------------------------------------------------------------
def _text(value: Any) -> str | None:
    return value if isinstance(value, str) and value.strip() else None


def _nonempty(value: Any) -> Any:
    return value if _text(value) is not None else _WRONG


def _names(value: Any) -> Any:
    if isinstance(value, list) and all(_text(v) is not None for v in value):
        return tuple(value)
    return _WRONG


def _names_or_empty(value: Any) -> Any:
    return () if value == [] else _names(value)


def _code_table(value: Any) -> Any:
    if not isinstance(value, dict):
        return _WRONG
    entries = []
    for pattern, codes in value.items():
        checked = _names_or_empty(codes)
        if checked is _WRONG:
            return _WRONG
        entries.append((pattern, checked))
    return tuple(entries)


def _integer(value: Any) -> Any:
    return value if isinstance(value, int) and not isinstance(value, bool) else _WRONG


_WRONG = object()

#: key -> (check returning the value or _WRONG, what the key must be)
_KEYS: Mapping[str, tuple[Callable[[Any], Any], str]] = {
    "behaviors": (_names, "a list of module names or file paths"),
    "catalog": (_nonempty, "a file path (text)"),
    "world": (_nonempty, "a file path (text)"),
    "seed": (_integer, "an integer"),
    "connect": (_nonempty, "a MAVLink endpoint (text), e.g. udpin:127.0.0.1:14550"),
    "disable_plugins": (_names, "a list of installed plugins' distribution names"),
    "verify": (lambda v: v if isinstance(v, dict) else _WRONG, "a table ([tool.aeroexec.verify])"),
}

_VERIFY_KEYS: Mapping[str, tuple[Callable[[Any], Any], str]] = {
    "catalogs": (_names_or_empty, "a list of catalog paths or glob patterns"),
    "missions": (_names_or_empty, "a list of mission paths or glob patterns"),
    "select": (_names_or_empty, "a list of rule codes or prefixes"),
    "extend-select": (_names_or_empty, "a list of rule codes or prefixes"),
    "ignore": (_names_or_empty, "a list of rule codes or prefixes"),
    "per-file-ignores": (_code_table, "a table of glob pattern = [codes or prefixes]"),
}


def _parse(path: Path, table: dict[str, Any]) -> ProjectConfig:
    values: dict[str, Any] = {}
    for key, value in table.items():
        known = _KEYS.get(key)
        if known is None and key == "tool" and path.name == AEROEXEC_TOML:
            raise ConfigError(
                f"in {AEROEXEC_TOML} the keys are at the top level, without a [{TABLE}] table",
                Mark(shown(path), 1, 1),
            )
        if known is None:
            raise ConfigError(f"unknown key '{key}'{_did_you_mean(key)}", key_mark(path, key))
        check, wanted = known
        checked = check(value)
        if checked is _WRONG:
            raise ConfigError(f"'{key}' must be {wanted}", key_mark(path, key))
        values[key] = checked
    if "verify" in values:
        values["verify"] = _parse_verify(path, values["verify"])
    root = path.parent
    return ProjectConfig(
        path=path,
        behaviors=values.get("behaviors"),
        catalog=_resolve(root, values.get("catalog")),
        world=_resolve(root, values.get("world")),
        seed=values.get("seed"),
        connect=values.get("connect"),
        disable_plugins=values.get("disable_plugins"),
        verify=values.get("verify"),
    )


def _parse_verify(path: Path, table: dict[str, Any]) -> VerifyConfig:
    values: dict[str, Any] = {}
    for key, value in table.items():
        known = _VERIFY_KEYS.get(key.replace("_", "-"))
        if known is None:
            raise ConfigError(
                f"unknown key 'verify.{key}' (keys: {', '.join(_VERIFY_KEYS)})",
                key_mark(path, key, "verify"),
            )
        check, wanted = known
        checked = check(value)
        if checked is _WRONG:
            raise ConfigError(f"'verify.{key}' must be {wanted}", key_mark(path, key, "verify"))
        values[key.replace("_", "-")] = checked
    root = path.parent
    return VerifyConfig(
        catalogs=tuple(str(_resolve(root, c)) for c in values.get("catalogs", ())),
        missions=tuple(str(_resolve(root, m)) for m in values.get("missions", ())),
        select=values.get("select"),
        extend_select=values.get("extend-select", ()),
        ignore=values.get("ignore", ()),
        per_file_ignores=values.get("per-file-ignores", ()),
    )


def _resolve(root: Path, name: str | None) -> Path | None:
    if name is None:
        return None
    path = Path(name).expanduser()
    return path if path.is_absolute() else root / path


def _did_you_mean(key: str) -> str:
    import difflib

    close = difflib.get_close_matches(key, list(_KEYS), n=1, cutoff=0.6)
    if close:
        return f" (did you mean '{close[0]}'?)"
    return f" (keys: {', '.join(_KEYS)})"


def key_mark(path: Path, key: str | None, table: str = "") -> Mark:
    """Where `key` is set in the aeroexec table, or in its subtable `table` (tomllib
    keeps no positions, so the text is searched: the table's header, then the key's
    line inside it)."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        return Mark(shown(path))
    start = 0
    if path.name == PYPROJECT or table:
        name = r"tool\s*\.\s*aeroexec" if path.name == PYPROJECT else ""
        if table:
            name = rf"{name}\s*\.\s*{table}" if name else table
        header = re.compile(rf"^\s*\[\s*{name}\s*\]")
        start = next((i for i, line in enumerate(lines) if header.match(line)), -1)
        if start < 0:
            return Mark(shown(path))
        if key is None:
            return Mark(shown(path), start + 1, 1)
        start += 1
    if key is None:
        return Mark(shown(path))
    pattern = re.compile(rf"^\s*[\"']?{re.escape(key)}[\"']?\s*=")
    for i in range(start, len(lines)):
        if lines[i].lstrip().startswith("[") and i > start:
            break
        if pattern.match(lines[i]):
            return Mark(shown(path), i + 1, lines[i].index(lines[i].lstrip()[0]) + 1)
    return Mark(shown(path), start if start else 0, 1 if start else 0)
