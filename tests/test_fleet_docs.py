"""docs/ci.md's shard matrix: valid YAML whose shards and merge fit together, and whose
commands, run as written for every shard, give the report of one unsharded replay."""

from __future__ import annotations

import re
import shlex
from pathlib import Path
from typing import Any

import pytest
import yaml
from test_replay_support import REPO
from typer.testing import CliRunner

from aeroexec.cli import app

DOC = REPO / "docs" / "ci.md"


def matrix_jobs() -> dict[str, Any]:
    blocks = re.findall(r"```yaml\n(.*?)```", DOC.read_text(encoding="utf-8"), re.S)
    jobs = [yaml.safe_load(b) for b in blocks]
    (found,) = [j for j in jobs if "replay-verdict" in j]
    return found


def run_of(job: dict[str, Any], name: str) -> str:
    return next(s["run"] for s in job["steps"] if s.get("name") == name)


def command(text: str, **values: str) -> list[str]:
    """The aeroexec command of a `run:` text, with ${{ matrix.X }} filled in."""
    for key, value in values.items():
        text = text.replace("${{ matrix." + key + " }}", value)
    line = next(x for x in text.replace("\\\n", " ").splitlines() if "aeroexec " in x)
    return shlex.split(line.split("aeroexec ", 1)[1])


def test_the_matrix_shards_and_merges_what_it_uploads() -> None:
    jobs = matrix_jobs()
    shards = jobs["replay"]["strategy"]["matrix"]["shard"]
    assert shards == list(range(1, len(shards) + 1))
    assert jobs["replay"]["strategy"]["fail-fast"] is False
    replay = run_of(jobs["replay"], "Replay this shard")
    assert f"--shard ${{{{ matrix.shard }}}}/{len(shards)}" in replay
    assert "--check" not in replay  # the merge decides
    upload = next(s for s in jobs["replay"]["steps"] if "upload-artifact" in s.get("uses", ""))
    download = next(
        s for s in jobs["replay-verdict"]["steps"] if "download-artifact" in s.get("uses", "")
    )
    assert re.fullmatch(
        download["with"]["pattern"].replace("*", ".*"),
        upload["with"]["name"].replace("${{ matrix.shard }}", "3"),
    )
    assert jobs["replay-verdict"]["needs"] == "replay"
    assert "aeroexec report merge shards/*.json --check" in run_of(
        jobs["replay-verdict"], "Merge the shards into one report"
    )


def test_the_documented_commands_give_the_unsharded_report(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    jobs = matrix_jobs()
    monkeypatch.chdir(REPO)
    # JUnit's timestamp and times are wall-clock facts; this makes both reports exact.
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")
    runner = CliRunner()
    replay = run_of(jobs["replay"], "Replay this shard")
    shards = tmp_path / "shards"
    shards.mkdir()
    for k in jobs["replay"]["strategy"]["matrix"]["shard"]:
        args = command(replay, shard=str(k))
        result = runner.invoke(app, args[: args.index(">")] if ">" in args else args)
        assert result.exit_code == 0, result.stderr
        (shards / f"shard-{k}.json").write_text(result.stdout, encoding="utf-8")
    merge = command(run_of(jobs["replay-verdict"], "Merge the shards into one report"))
    assert merge[:3] == ["report", "merge", "shards/*.json"]
    merge = [str(p) for p in sorted(shards.iterdir())] + merge[3:]  # the glob, expanded
    output = merge[merge.index("-o") + 1]
    result = runner.invoke(app, ["report", "merge", *merge])
    assert result.exit_code == 0, result.stderr
    whole = runner.invoke(
        app, ["replay", "recordings/", "--catalog", "catalog/default.yaml", "--format", "junit"]
    )
    assert Path(output).read_text(encoding="utf-8") == whole.stdout
    Path(output).unlink()
