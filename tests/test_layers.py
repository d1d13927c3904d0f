"""Layers point down (issue 23): every import of every module of aeroexec, read with `ast`
(those inside functions and under `TYPE_CHECKING` too), goes to its own package, a support
module or a package of a lower row of the layer table in docs/design.md#layers. The table
is read from the document, so the design and the code cannot drift apart."""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
#: Where the layer table is: the file, and the section `read_layers` reads.
SECTION = "docs/design.md#layers"
DESIGN = ROOT / SECTION.partition("#")[0]
PACKAGE = ROOT / "aeroexec"

#: The root module `python -m aeroexec` runs: the command line, the top row.
ENTRY = "__main__"


@dataclass(frozen=True, slots=True)
class Layers:
    #: Package name -> its row, 0 at the top (cli).
    rows: dict[str, int]
    #: The root modules (`errors`, `inputs`, ...) any layer may use.
    support: frozenset[str]


@dataclass(frozen=True, slots=True)
class Import:
    path: Path
    line: int
    #: The dotted name imported (`aeroexec.vehicles.base`).
    target: str


def packages(root: Path = PACKAGE) -> set[str]:
    return {p.parent.name for p in root.glob("*/__init__.py")}


def root_modules(root: Path = PACKAGE) -> set[str]:
    return {p.stem for p in root.glob("*.py")} - {"__init__", ENTRY}


def read_layers(text: str, known: set[str]) -> Layers:
    """The `### Layers` code block: each line's leading package names are one row (the
    description follows them); and the backticked `NAME.py` of the paragraph that begins
    "Support modules"."""
    section = text.split("### Layers", 1)[1]
    block = section.split("```", 2)[1]
    rows: dict[str, int] = {}
    for number, line in enumerate(line for line in block.splitlines() if line.strip()):
        names = []
        for word in line.split():
            if word not in known:
                break
            names.append(word)
        assert names, f"docs/design.md#layers: a row without a package: {line!r}"
        for name in names:
            assert name not in rows, f"docs/design.md#layers: {name} is in two rows"
            rows[name] = number
    paragraph = re.search(r"^Support modules.*?(?:\n\n|\Z)", section, re.M | re.S)
    assert paragraph, "docs/design.md#layers has no 'Support modules' paragraph"
    support = frozenset(re.findall(r"`([a-z_]+)\.py`", paragraph[0]))
    return Layers(rows, support)


def module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imports(path: Path, root: Path = PACKAGE) -> list[Import]:
    """Every `import` and `from ... import` in the file, at any depth, as the absolute
    dotted name of the module imported from; `from aeroexec import x` names `aeroexec.x`."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    name = module_name(path, root)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [Import(path, node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*anchor, *([base] if base else [])])
            if "." in base:  # `from aeroexec.x.y import a, b`: one import of aeroexec.x.y
                found.append(Import(path, node.lineno, base))
            else:  # `from aeroexec import x`: x may be a package
                found += [Import(path, node.lineno, f"{base}.{a.name}") for a in node.names]
    return [i for i in found if i.target.split(".")[0] == root.name]


def place(dotted: str) -> str | None:
    """The package or root module a dotted name lies in (None: the root package)."""
    parts = dotted.split(".")
    return parts[1] if len(parts) > 1 else None


def violations(layers: Layers, root: Path = PACKAGE) -> list[str]:
    """One line per import that runs up the layers or across a row."""
    found = []
    for path in sorted(root.rglob("*.py")):
        own = place(module_name(path, root))
        if own == ENTRY:
            own = "cli"
        for item in imports(path, root):
            target = place(item.target)
            where = f"{item.path.relative_to(root.parent)}:{item.line}"
            if target is None or target == own:
                continue
            if target not in layers.rows and target not in layers.support:
                continue  # a name of the root package (`__version__`), not a module
            if own in layers.support:
                if target not in layers.support:
                    found.append(f"{where}: support module {own} imports {item.target}")
                continue
            if target in layers.support:
                continue
            if layers.rows[target] <= layers.rows[own]:
                how = "a neighbour in its row" if layers.rows[target] == layers.rows[own] else "up"
                found.append(f"{where}: {own} imports {item.target} ({how})")
    return found


@pytest.fixture(scope="module")
def layers() -> Layers:
    return read_layers(DESIGN.read_text(encoding="utf-8"), packages())


def test_every_package_has_a_row_and_every_root_module_is_support(layers: Layers) -> None:
    assert set(layers.rows) == packages()
    assert layers.support == root_modules()


def test_the_package_table_names_every_package() -> None:
    text = DESIGN.read_text(encoding="utf-8").split("### Layers", 1)[1]
    table = set(re.findall(r"^\| `([a-z_]+)/` \|", text, re.M))
    assert table == packages()


def test_no_import_runs_up_the_layers_or_across_a_row(layers: Layers) -> None:
    assert violations(layers) == []


# -- the check itself can fail ---------------------------------------------------------


TABLE = """### Layers

```
top               commands
left  right       tools
low               the bottom
```

Support modules every layer may use: `errors.py` (errors).
"""


def fake_tree(tmp_path: Path, files: dict[str, str]) -> Path:
    root = tmp_path / "aeroexec"
    for name in ("top", "left", "right", "low"):
        (root / name).mkdir(parents=True)
        (root / name / "__init__.py").write_text("")
    (root / "__init__.py").write_text("__version__ = '0'\n")
    (root / "errors.py").write_text("")
    for name, text in files.items():
        (root / name).write_text(text)
    return root


def test_the_table_is_read_as_rows_and_support_modules() -> None:
    layers = read_layers(TABLE, {"top", "left", "right", "low"})
    assert layers.rows == {"top": 0, "left": 1, "right": 1, "low": 2}
    assert layers.support == {"errors"}


def test_downward_own_package_and_support_imports_pass(tmp_path: Path) -> None:
    root = fake_tree(
        tmp_path,
        {
            "top/a.py": "import aeroexec.left.x\nfrom aeroexec.low import y\n",
            "left/b.py": "from aeroexec import __version__\nfrom . import c\n"
            "from aeroexec.errors import E\nfrom aeroexec.low.z import w\n",
        },
    )
    layers = read_layers(TABLE, {"top", "left", "right", "low"})
    assert violations(layers, root) == []


def test_upward_sibling_and_hidden_imports_are_found(tmp_path: Path) -> None:
    root = fake_tree(
        tmp_path,
        {
            "low/up.py": "from aeroexec.left.x import thing\n",
            "left/across.py": "import aeroexec.right\n",
            "low/inner.py": "def f():\n    from aeroexec.top import a\n",
            "low/typing_only.py": "from typing import TYPE_CHECKING\n"
            "if TYPE_CHECKING:\n    from ..left import x\n",
            "errors.py": "from aeroexec.low import y\n",
            "right/named.py": "from aeroexec import left\n",
        },
    )
    layers = read_layers(TABLE, {"top", "left", "right", "low"})
    assert violations(layers, root) == [
        "aeroexec/errors.py:1: support module errors imports aeroexec.low",
        "aeroexec/left/across.py:1: left imports aeroexec.right (a neighbour in its row)",
        "aeroexec/low/inner.py:2: low imports aeroexec.top (up)",
        "aeroexec/low/typing_only.py:3: low imports aeroexec.left (up)",
        "aeroexec/low/up.py:1: low imports aeroexec.left.x (up)",
        "aeroexec/right/named.py:1: right imports aeroexec.left (a neighbour in its row)",
    ]
