"""constraints.txt pins every dependency, and CI runs exactly the README's test command.

A fresh clone must install the versions the suite last passed with: a dependency that
pyproject.toml names but constraints.txt does not pin could move under CI on any day.
"""

from __future__ import annotations

import os
import re
import tomllib
from importlib import metadata
from pathlib import Path

import pytest
from packaging.markers import default_environment
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

ROOT = Path(__file__).resolve().parent.parent


def pins() -> dict[str, str]:
    """Name -> version of every pin that applies to the running Python."""
    found: dict[str, str] = {}
    for line in (ROOT / "constraints.txt").read_text().splitlines():
        if not line.strip() or line.startswith("#"):
            continue
        requirement = Requirement(line)
        if requirement.marker is not None and not requirement.marker.evaluate():
            continue
        (specifier,) = requirement.specifier
        assert specifier.operator == "==", line
        found[canonicalize_name(requirement.name)] = specifier.version
    return found


def declared() -> list[Requirement]:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    lines = list(project["dependencies"])
    for extra in project["optional-dependencies"].values():
        lines.extend(extra)
    return [Requirement(line) for line in lines]


def test_every_declared_dependency_is_pinned() -> None:
    pinned = pins()
    environment = default_environment()
    missing = [
        str(r)
        for r in declared()
        if (r.marker is None or r.marker.evaluate(environment))
        and canonicalize_name(r.name) not in pinned
    ]
    assert missing == []
    # Each pin also satisfies what pyproject.toml asks for.
    for requirement in declared():
        version = pinned.get(canonicalize_name(requirement.name))
        if version is not None:
            assert requirement.specifier.contains(version, prereleases=True), requirement


@pytest.mark.skipif(
    os.environ.get("AEROEXEC_TEST_NEWEST") == "1", reason="scripts/test-newest: unpinned on purpose"
)
def test_the_suite_runs_on_the_pinned_versions() -> None:
    pinned = pins()
    for requirement in declared():
        name = canonicalize_name(requirement.name)
        try:
            installed = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue  # an extra this venv did not install (ray's dashboard, say)
        assert installed == pinned[name], f"{name} {installed} installed, {pinned[name]} pinned"


def test_ci_runs_the_readmes_test_command_through_the_constraints() -> None:
    readme = (ROOT / "README.md").read_text()
    ci = (ROOT / ".ci" / "run").read_text()
    commands = re.findall(r"^python3 -m venv \.venv && .*$", readme, flags=re.M)
    test_command = next(c for c in commands if "pytest" in c)
    assert test_command in ci.splitlines()
    assert all("-c constraints.txt" in c for c in commands)


def test_the_readmes_commands_to_move_and_to_try_the_pins_exist() -> None:
    # Issue 23: one documented command keeps constraints.txt current, a second tests
    # against the newest releases; a README naming a script that is gone helps no one.
    readme = " ".join((ROOT / "README.md").read_text().split())
    named = set(re.findall(r"`(scripts/[\w-]+)`", readme))
    assert {"scripts/update-constraints", "scripts/test-newest"} <= named
    for script in named:
        path = ROOT / script
        assert path.is_file() and os.access(path, os.X_OK), script
    lines = (ROOT / "constraints.txt").read_text().splitlines()
    header = " ".join(line for line in lines if line.startswith("#"))
    assert "scripts/update-constraints" in header and "scripts/test-newest" in header
    # The refresh writes the very file CI installs through.
    refresh = (ROOT / "scripts" / "update-constraints").read_text()
    assert "mv constraints.txt.new constraints.txt" in refresh
