"""Issue 23: one broken installed plugin must not take every command down with no way
out. A real distribution (a .dist-info directory with entry_points.txt on the path of a
real `aeroexec` subprocess) whose module fails to import: `run` of the bundled mission
and `behaviors` say so in one line naming the distribution and the two opt-outs, and
each opt-out (AEROEXEC_DISABLE_PLUGIN_AUTOLOAD, --disable-plugin, the configuration's
disable_plugins) gives the run of a machine without the plugin. A project's own
behavior replaces an installed plugin's of the same name, with a note.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from aeroexec.catalog import DEFAULT_CATALOG

REPO = Path(__file__).resolve().parent.parent
MISSION = REPO / "missions" / "appendix_c.py"

BEHAVIOR = """\
from aeroexec.executive import Finished
from aeroexec.behaviors import Land


class {cls}(Land):
    def on_run(self):
        print("{cls} ran")
        return super().on_run()
"""


def install(site: Path, dist: str, module: str, text: str) -> Path:
    """A real installed distribution providing `module` as an `aeroexec.behaviors`
    entry point; returns its entry_points.txt."""
    info = site / f"{dist}-1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(f"[aeroexec.behaviors]\ntricks = {module}\n")
    (site / f"{module}.py").write_text(text)
    return info / "entry_points.txt"


def aeroexec(cwd: Path, site: Path, *args: str, **env: str) -> subprocess.CompletedProcess[str]:
    environ = {k: v for k, v in os.environ.items() if not k.startswith("AEROEXEC_")}
    environ |= {"PYTHONPATH": str(site), **env}
    return subprocess.run(
        [sys.executable, "-m", "aeroexec", *args],
        cwd=cwd,
        env=environ,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_a_broken_plugin_is_one_line_naming_it_and_every_opt_out_runs_without_it(
    tmp_path: Path,
) -> None:
    site = tmp_path / "site"
    install(site, "drone_tricks", "drone_tricks_behaviors", "import missing_dependency_xyz\n")
    work = tmp_path / "work"
    work.mkdir()
    expected_line = (
        f"{site / 'drone_tricks_behaviors.py'}:1:1: error: installed plugin drone_tricks 1.0 "
        "(entry point tricks = drone_tricks_behaviors) failed to load: ModuleNotFoundError: "
        "No module named 'missing_dependency_xyz'; turn it off with --disable-plugin "
        "drone_tricks (or every installed plugin with AEROEXEC_DISABLE_PLUGIN_AUTOLOAD=1)"
    )
    for command in (["run", str(MISSION), "-q"], ["behaviors"]):
        done = aeroexec(work, site, *command)
        assert (done.returncode, done.stdout) == (2, ""), done.stderr
        assert done.stderr.splitlines() == [expected_line]

    plain = aeroexec(work, tmp_path / "nothing-installed", "run", str(MISSION), "-q")
    assert plain.returncode == 0, plain.stderr
    (work / "aeroexec.toml").write_text('disable_plugins = ["Drone-Tricks"]\n')
    configured = aeroexec(work, site, "run", str(MISSION), "-q")
    (work / "aeroexec.toml").unlink()
    for done in (
        aeroexec(work, site, "run", str(MISSION), "-q", AEROEXEC_DISABLE_PLUGIN_AUTOLOAD="1"),
        aeroexec(work, site, "run", str(MISSION), "-q", "--disable-plugin", "drone-tricks"),
        configured,
    ):
        assert (done.returncode, done.stdout, done.stderr) == (0, plain.stdout, plain.stderr)

    listed = aeroexec(work, site, "behaviors", "--disable-plugin", "drone_tricks")
    assert listed.returncode == 0, listed.stderr
    assert (
        "looked in: entry points 'aeroexec.behaviors' (1 installed, 1 turned off); "
        "the standard library" in listed.stdout
    )


def test_the_projects_behavior_replaces_an_installed_plugins_and_says_so(tmp_path: Path) -> None:
    site = tmp_path / "site"
    install(site, "drone_tricks", "drone_tricks_land", BEHAVIOR.format(cls="InstalledLand"))
    work = tmp_path / "work"
    work.mkdir()
    (work / "mine.py").write_text(BEHAVIOR.format(cls="ProjectLand"))
    recording = work / "flight.mcap"
    done = aeroexec(work, site, "run", str(MISSION), "-b", "mine.py", "-o", str(recording))
    assert done.returncode == 0, done.stderr
    assert "ProjectLand ran" in done.stdout and "InstalledLand ran" not in done.stdout
    assert done.stderr.splitlines() == [
        "aeroexec run: note: LAND: mine:ProjectLand (mine.py:5, from --behaviors "
        "mine.py) replaces the installed plugin's drone_tricks_land:InstalledLand (from "
        "tricks = drone_tricks_land (drone_tricks 1.0))"
    ]
    # Without the project's, the installed one flies.
    installed = aeroexec(work, site, "run", str(MISSION))
    assert installed.returncode == 0 and "InstalledLand ran" in installed.stdout
    # `behaviors` shows who replaced whom.
    listed = aeroexec(work, site, "behaviors", "-b", "mine.py", "-c", str(DEFAULT_CATALOG))
    row = next(line for line in listed.stdout.splitlines() if line.startswith("LAND "))
    assert "replaces installed tricks = drone_tricks_land (drone_tricks 1.0)" in row
