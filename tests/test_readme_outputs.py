"""Issue 23: the README's commands, run from a clone's root, leave nothing that `git
status` shows: every file they write (`-o FILE`, and the `.rrd` that `view` writes beside
a recording) is ignored by the repository's .gitignore, while the committed recordings
are not."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"


def written() -> set[str]:
    """Every relative file a README command writes: the lines of its code blocks and its
    inline code (which prose may wrap over two lines)."""
    text = README.read_text(encoding="utf-8")
    commands = [
        line for block in re.findall(r"```\w*\n(.*?)```", text, re.S) for line in block.splitlines()
    ]
    prose = re.sub(r"```.*?```", "", text, flags=re.S)
    commands += [span.replace("\n", " ") for span in re.findall(r"`([^`]+)`", prose)]
    found: set[str] = set()
    for command in commands:
        for match in re.finditer(r"aeroexec (\w+)([^#]*)", command):
            found.update(re.findall(r"(?:-o|--output) (\S+)", match[0]))
            if match[1] == "view":
                found.add(str(Path(match[2].split()[0]).with_suffix(".rrd")))
    return {f for f in found if not f.startswith(("/", "-", "<")) and not f.split(".")[0].isupper()}


def ignored(paths: list[str]) -> set[str]:
    done = subprocess.run(
        ["git", "check-ignore", "--no-index", "--stdin"],
        cwd=ROOT,
        input="\n".join(paths) + "\n",
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode in (0, 1), done.stderr
    return set(done.stdout.split())


def test_what_the_readme_writes_is_ignored_and_the_recordings_are_not() -> None:
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout: .gitignore does not apply")
    outputs = written()
    assert {"flight.mcap", "flight.rrd", "out/appendix_c.mcap", "layout.json"} <= outputs
    assert ignored(sorted(outputs)) == outputs
    committed = [str(p.relative_to(ROOT)) for p in (ROOT / "recordings").glob("*.mcap")]
    assert committed and ignored(committed) == set()
