"""Where behaviors come from: --behaviors, the project configuration, installed entry
points, the standard library; overriding, duplicates, and every way a plugin can be bad
(one BehaviorError naming the file and line)."""

from __future__ import annotations

import sys
import textwrap
from pathlib import Path

import pytest

from aeroexec.behaviors import STANDARD_LIBRARY, GoToPoint
from aeroexec.config import load_config
from aeroexec.errors import BehaviorError
from aeroexec.plugins import BehaviorSources, discover, sources_for

BEHAVIOR = """\
from aeroexec.executive import Behavior, Finished


class {cls}(Behavior):
    name = "{name}"

    def on_run(self):
        return Finished()
"""


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def cli(*specs: str | Path, root: Path | None = None) -> BehaviorSources:
    return BehaviorSources(
        command_line=tuple(str(s) for s in specs),
        command_line_root=str(root or Path.cwd()),
        entry_points=False,
    )


def error_of(sources: BehaviorSources) -> BehaviorError:
    with pytest.raises(BehaviorError) as caught:
        discover(sources)
    return caught.value


# -- sources and their order --------------------------------------------------------------
def test_a_file_adds_behaviors_and_overrides_a_standard_one(tmp_path: Path) -> None:
    write(
        tmp_path / "mine.py",
        """\
        from aeroexec.behaviors import GoToPoint
        from aeroexec.executive import Behavior


        class Survey(Behavior):
            name = "SURVEY"


        class PreciseGoToPoint(GoToPoint):
            tolerance = 0.01
        """,
    )
    found = discover(cli(tmp_path / "mine.py"))
    survey, go_to = found.implementations["SURVEY"], found.implementations["GO_TO_POINT"]
    assert survey.reference == "mine:Survey" and survey.source == "--behaviors"
    assert not survey.overrides
    assert go_to.reference == "mine:PreciseGoToPoint" and go_to.overrides
    assert go_to.cls.tolerance == 0.01 and issubclass(go_to.cls, GoToPoint)
    # The rest is the standard library, untouched; the imported GoToPoint is not offered.
    assert found.implementations["LAND"].cls is STANDARD_LIBRARY["LAND"]
    assert found.implementations["LAND"].standard
    assert set(found.implementations) == {*STANDARD_LIBRARY, "SURVEY"}
    assert found.declared
    assert found.searched == (f"--behaviors {tmp_path / 'mine.py'}", "the standard library")


def test_the_configuration_resolves_names_against_its_directory(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    project = tmp_path / "project"
    write(project / "pyproject.toml", '[tool.aeroexec]\nbehaviors = ["flying.tricks"]\n')
    write(project / "flying" / "__init__.py", "")
    write(
        project / "flying" / "tricks.py",
        "from .base import Trick\n\n\nclass Loop(Trick):\n    name = 'LOOP'\n",
    )
    write(project / "flying" / "base.py", BEHAVIOR.format(cls="Trick", name=""))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(project / "flying")  # a subdirectory of the project
    config = load_config()
    found = discover(sources_for([], config))
    loop = found.implementations["LOOP"]
    assert loop.reference == "flying.tricks:Loop"
    # Outside the working directory, so shown in full.
    assert loop.source == str((project / "pyproject.toml").resolve())
    assert loop.origin == "flying.tricks"
    assert "LOOP" in found.implementations and "" not in found.implementations
    assert found.searched[0].endswith("pyproject.toml [tool.aeroexec] behaviors (flying.tricks)")


def test_an_empty_behaviors_list_still_declares_the_project(tmp_path: Path) -> None:
    write(tmp_path / "aeroexec.toml", "behaviors = []\n")
    found = discover(sources_for([], load_config(tmp_path)))
    assert found.declared
    assert set(found.implementations) == set(STANDARD_LIBRARY)
    assert not discover(BehaviorSources(entry_points=False)).declared


def test_two_user_sources_implementing_one_name_is_an_error_naming_both(tmp_path: Path) -> None:
    write(tmp_path / "a.py", BEHAVIOR.format(cls="First", name="SURVEY"))
    second = write(tmp_path / "b.py", "\n\n" + BEHAVIOR.format(cls="Second", name="SURVEY"))
    error = error_of(cli(tmp_path / "a.py", tmp_path / "b.py"))
    assert error.mark is not None
    assert Path(error.mark.file).resolve() == second.resolve() and error.mark.line == 6
    assert "behavior SURVEY is implemented twice" in error.message
    assert "b:Second" in error.message and "a:First" in error.message
    assert "a.py:4" in error.message


def test_naming_one_module_twice_is_not_a_duplicate(tmp_path: Path) -> None:
    write(tmp_path / "a.py", BEHAVIOR.format(cls="First", name="SURVEY"))
    found = discover(cli(tmp_path / "a.py", "a", root=tmp_path))
    assert found.implementations["SURVEY"].reference == "a:First"


def test_all_says_what_a_module_offers(tmp_path: Path) -> None:
    write(
        tmp_path / "pkg" / "__init__.py",
        """\
        from aeroexec.executive import Behavior


        class Base(Behavior):
            name = "SURVEY"


        class Fast(Base):
            speed = 3.0


        __all__ = ["Fast"]
        """,
    )
    found = discover(cli(tmp_path / "pkg"))
    assert found.implementations["SURVEY"].reference == "pkg:Fast"
    del_all = (tmp_path / "pkg" / "__init__.py").read_text().replace('__all__ = ["Fast"]', "")
    (tmp_path / "pkg" / "__init__.py").write_text(del_all)
    error = error_of(cli(tmp_path / "pkg"))
    assert "implemented twice" in error.message and "__all__" in error.message


def test_an_edited_file_is_imported_afresh(tmp_path: Path) -> None:
    path = write(
        tmp_path / "tune.py",
        "from aeroexec.behaviors import GoToPoint\n\n\n"
        "class Tuned(GoToPoint):\n    tolerance = 0.04\n",
    )
    assert discover(cli(path)).implementations["GO_TO_POINT"].cls.tolerance == 0.04
    path.write_text(path.read_text().replace("0.04", "0.02"))
    assert discover(cli(path)).implementations["GO_TO_POINT"].cls.tolerance == 0.02


# -- bad plugins: one error naming the file ------------------------------------------------
@pytest.mark.parametrize(
    ("files", "spec", "where", "message"),
    [
        (
            {"broken.py": "import math\nimport no_such_dependency_xyz\n"},
            "broken.py",
            ("broken.py", 2),
            "importing --behaviors broken.py failed: ModuleNotFoundError: "
            "No module named 'no_such_dependency_xyz'",
        ),
        (
            {"deep.py": "from helper import value\n", "helper.py": "x = 1\nvalue = 1 / 0\n"},
            "deep.py",
            ("helper.py", 2),
            "ZeroDivisionError: division by zero",
        ),
        (
            {"syntax.py": "from aeroexec.executive import Behavior\n\nclass S(Behavior)\n"},
            "syntax.py",
            ("syntax.py", 3),
            "invalid Python: expected ':'",
        ),
        (
            {
                "plain.py": "class Survey:\n    name = 'SURVEY'\n\n"
                "    def on_run(self):\n        return None\n"
            },
            "plain.py",
            ("plain.py", 1),
            "Survey has behavior hooks but is not a subclass of aeroexec.executive.Behavior",
        ),
        (
            {"double.py": BEHAVIOR.format(cls="A", name="X") + BEHAVIOR.format(cls="B", name="X")},
            "double.py",
            ("double.py", 12),
            "behavior X is implemented twice: double:B",
        ),
        (
            {"nothing.py": "VALUE = 1\n"},
            "nothing.py",
            ("nothing.py", 0),
            "nothing provides no behavior",
        ),
        (
            {
                "listed.py": BEHAVIOR.format(cls="A", name="X")
                + "\nVALUE = 1\n__all__ = ['A', 'VALUE']\n"
            },
            "listed.py",
            ("listed.py", 0),
            "VALUE is in __all__ but is not a Behavior subclass",
        ),
        ({"notes.txt": "hello\n"}, "notes.txt", ("notes.txt", 0), "not a .py file"),
    ],
    ids=[
        "import-error",
        "error-in-helper",
        "syntax-error",
        "not-a-behavior",
        "duplicate",
        "no-behavior",
        "all-not-behavior",
        "not-python",
    ],
)
def test_a_bad_plugin_is_one_error_at_its_file_and_line(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    files: dict[str, str],
    spec: str,
    where: tuple[str, int],
    message: str,
) -> None:
    for name, text in files.items():
        write(tmp_path / name, text)
    monkeypatch.chdir(tmp_path)
    error = error_of(cli(spec, root=tmp_path))
    assert error.mark is not None, str(error)
    assert (error.mark.file, error.mark.line) == where, str(error)
    assert message in error.message
    assert "\n" not in str(error)


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("no_such_behaviors_xyz", "no module named 'no_such_behaviors_xyz'"),
        ("missing.py", "no such file or directory: missing.py"),
        ("folder", "is a directory without __init__.py"),
    ],
)
def test_a_plugin_that_is_not_there_is_reported_where_it_was_named(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, spec: str, message: str
) -> None:
    (tmp_path / "folder").mkdir()
    monkeypatch.chdir(tmp_path)
    error = error_of(cli(spec, root=tmp_path))
    assert error.mark is None
    assert str(error).startswith(f"--behaviors {spec}: ") and message in str(error)
    # Named by the configuration instead: the error points at its `behaviors` line.
    write(tmp_path / "pyproject.toml", f'[tool.aeroexec]\nseed = 1\nbehaviors = ["{spec}"]\n')
    error = error_of(sources_for([], load_config(tmp_path)))
    assert error.mark is not None
    assert (error.mark.file, error.mark.line) == ("pyproject.toml", 3)
    assert error.message.startswith(f"behaviors entry '{spec}': ") and message in error.message


# -- installed entry points ----------------------------------------------------------------
def install(site: Path, dist: str, entries: str, modules: dict[str, str]) -> None:
    """A real installed distribution: a .dist-info directory with entry_points.txt."""
    info = site / f"{dist}-1.0.dist-info"
    write(info / "METADATA", f"Metadata-Version: 2.1\nName: {dist}\nVersion: 1.0\n")
    write(info / "entry_points.txt", f"[aeroexec.behaviors]\n{entries}\n")
    for name, text in modules.items():
        write(site / name, text)


def test_entry_points_of_installed_packages_are_found(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    site = tmp_path / "site"
    install(
        site,
        "dronetricks",
        "tricks = dronetricks_behaviors\nsingle = dronetricks_single:Hover",
        {
            "dronetricks_behaviors.py": BEHAVIOR.format(cls="Loop", name="LOOP"),
            "dronetricks_single.py": BEHAVIOR.format(cls="Hover", name="KEEP_HOVERING"),
        },
    )
    monkeypatch.syspath_prepend(str(site))
    found = discover(BehaviorSources())
    assert found.declared
    loop, hover = found.implementations["LOOP"], found.implementations["KEEP_HOVERING"]
    assert loop.source == "entry point" and "dronetricks 1.0" in loop.origin
    assert hover.reference == "dronetricks_single:Hover" and hover.overrides
    assert "entry points 'aeroexec.behaviors' (2 installed)" in found.searched
    assert found.notes() == ()


def test_the_projects_own_behavior_replaces_an_installed_plugins_with_a_note(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The README's order is a precedence: --behaviors (and the configuration) before
    installed plugins, before the standard library."""
    site = tmp_path / "site"
    install(
        site,
        "dronetricks",
        "tricks = dronetricks_behaviors",
        {"dronetricks_behaviors.py": BEHAVIOR.format(cls="Loop", name="LOOP")},
    )
    monkeypatch.syspath_prepend(str(site))
    write(tmp_path / "mine.py", BEHAVIOR.format(cls="MyLoop", name="LOOP"))
    found = discover(BehaviorSources(command_line=(str(tmp_path / "mine.py"),)))
    loop = found.implementations["LOOP"]
    assert (loop.reference, loop.source) == ("mine:MyLoop", "--behaviors")
    assert loop.shadows is not None and loop.shadows.reference == "dronetricks_behaviors:Loop"
    (note,) = found.notes()
    assert note.startswith("LOOP: mine:MyLoop (") and str(tmp_path / "mine.py") in note
    assert note.endswith(
        "replaces the installed plugin's dronetricks_behaviors:Loop "
        "(from tricks = dronetricks_behaviors (dronetricks 1.0))"
    )
    # The same from the project configuration.
    write(tmp_path / "aeroexec.toml", 'behaviors = ["mine.py"]\n')
    found = discover(sources_for(config=load_config(tmp_path)))
    assert found.implementations["LOOP"].reference == "mine:MyLoop" and found.notes()


def test_two_installed_plugins_implementing_one_name_is_an_error_naming_both(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    site = tmp_path / "site"
    install(site, "alpha", "a = alpha_b", {"alpha_b.py": BEHAVIOR.format(cls="A", name="LOOP")})
    install(site, "beta", "b = beta_b", {"beta_b.py": BEHAVIOR.format(cls="B", name="LOOP")})
    monkeypatch.syspath_prepend(str(site))
    error = error_of(BehaviorSources())
    assert "behavior LOOP is implemented twice" in error.message
    assert "(alpha 1.0)" in error.message and "(beta 1.0)" in error.message
    assert "turn one off with --disable-plugin NAME" in error.message
    # Turning one off settles it, and only the other is imported.
    found = discover(BehaviorSources(disabled_plugins=("Beta",)))
    assert found.implementations["LOOP"].reference == "alpha_b:A"
    assert "entry points 'aeroexec.behaviors' (2 installed, 1 turned off)" in found.searched


DISABLE_HINT = (
    "turn it off with --disable-plugin {name} "
    "(or every installed plugin with AEROEXEC_DISABLE_PLUGIN_AUTOLOAD=1)"
)


def test_an_entry_point_naming_something_else_is_an_error_at_its_declaration(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    site = tmp_path / "site"
    install(site, "oddity", "odd = oddity_mod:VALUE", {"oddity_mod.py": "VALUE = 3\n"})
    monkeypatch.syspath_prepend(str(site))
    error = error_of(BehaviorSources())
    declared = site / "oddity-1.0.dist-info" / "entry_points.txt"
    assert error.mark is not None
    assert (error.mark.file, error.mark.line) == (str(declared), 2)
    assert error.message == (
        "installed plugin oddity 1.0 (entry point odd = oddity_mod:VALUE) names int, not a "
        "module or a Behavior subclass; " + DISABLE_HINT.format(name="oddity")
    )


@pytest.mark.parametrize(
    ("module", "line", "problem"),
    [
        ("import nonexistent_dependency_xyz\n", 1, "failed to load: ModuleNotFoundError"),
        ("X = 1\n\nraise RuntimeError('no licence')\n", 3, "failed to load: RuntimeError"),
        ("def broken(:\n", 1, "is not valid Python"),
        ("X = 1\n", 0, "{module} provides no behavior"),
        (None, 2, "failed to load: ModuleNotFoundError: No module named '{module}'"),
    ],
)
def test_a_broken_plugin_names_its_distribution_and_the_way_to_turn_it_off_once(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    module: str | None,
    line: int,
    problem: str,
) -> None:
    site = tmp_path / "site"
    name = f"broken_tricks_{tmp_path.name}"  # one module per case: none is imported yet
    name = "".join(c if c.isalnum() else "_" for c in name)
    problem = problem.format(module=name)
    files = {f"{name}.py": module} if module is not None else {}
    install(site, "Broken_Tricks", f"tricks = {name}", files)
    monkeypatch.syspath_prepend(str(site))
    error = error_of(BehaviorSources())
    assert error.mark is not None
    expected = site / (f"{name}.py" if module else "Broken_Tricks-1.0.dist-info/entry_points.txt")
    assert (error.mark.file, error.mark.line) == (str(expected), line)
    what = f"installed plugin Broken_Tricks 1.0 (entry point tricks = {name})"
    assert error.message.startswith(what) and problem in error.message
    assert error.message.endswith("; " + DISABLE_HINT.format(name="Broken_Tricks"))
    assert error.message.count(name) == 1 + problem.count(name)  # the entry point: once
    # Every opt-out leaves it unimported: the standard library answers.
    sys.modules.pop(name, None)
    for disabled in ("broken-tricks", "BROKEN.TRICKS", "tricks"):  # pip's spellings, or the
        found = discover(BehaviorSources(disabled_plugins=(disabled,)))  # entry point's name
        assert found.implementations["LAND"].standard and not found.user()
        assert name not in sys.modules
    monkeypatch.setenv("AEROEXEC_DISABLE_PLUGIN_AUTOLOAD", "1")
    found = discover(sources_for())
    assert found.implementations["LAND"].standard and not found.declared
    assert (
        "entry points 'aeroexec.behaviors' (not loaded: AEROEXEC_DISABLE_PLUGIN_AUTOLOAD is set)"
        in (found.searched)
    )
    # ... and the configuration's disable_plugins, without the variable.
    monkeypatch.delenv("AEROEXEC_DISABLE_PLUGIN_AUTOLOAD")
    write(tmp_path / "aeroexec.toml", 'disable_plugins = ["broken.tricks"]\n')
    assert not discover(sources_for(config=load_config(tmp_path))).user()
    monkeypatch.setenv("AEROEXEC_DISABLE_PLUGIN_AUTOLOAD", "0")  # "0" is not "set"
    assert error_of(sources_for()).message == error.message


def test_a_package_without_all_provides_its_public_submodules(tmp_path: Path) -> None:
    write(tmp_path / "fleet" / "__init__.py", "")
    write(tmp_path / "fleet" / "survey.py", BEHAVIOR.format(cls="Survey", name="SURVEY"))
    write(tmp_path / "fleet" / "deep" / "__init__.py", "")
    write(tmp_path / "fleet" / "deep" / "orbit.py", BEHAVIOR.format(cls="Orbit", name="ORBIT"))
    write(tmp_path / "fleet" / "_private.py", "raise RuntimeError('never imported')\n")
    found = discover(cli(tmp_path / "fleet"))
    assert found.implementations["SURVEY"].reference == "fleet.survey:Survey"
    assert found.implementations["ORBIT"].reference == "fleet.deep.orbit:Orbit"
    write(tmp_path / "fleet" / "broken.py", "x = (\n")
    error = error_of(cli(tmp_path / "fleet"))
    assert error.mark is not None and error.mark.file.endswith("fleet/broken.py")
    assert error.mark.line == 1 and "invalid Python" in error.message
