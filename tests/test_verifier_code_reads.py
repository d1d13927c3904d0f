"""AX903/AX904 for a behavior that declares no argument names: the names its hooks read
are found in the AST of its source (never by running it), and compared with the
catalog. `aeroexec run` shows what the mismatch does in flight."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest
from typer.testing import CliRunner

from aeroexec.cli import app
from aeroexec.verifier.code_reads import arguments_read

runner = CliRunner()

BEHAVIOR = """\
from aeroexec.executive import Behavior, Finished
from aeroexec.executive.messages import EventCode


class Measure(Behavior):
    name = "MEASURE"

    def on_start(self, args):
        self.limit = args["TEMPERATURE"]
        self.unit = args.get("UNIT", "C")

    def on_run(self):
        if "PRECISION" in self.arguments:
            pass
        return Finished(EventCode.GOAL_ACHIEVED)
"""

CATALOG = """\
behavior_descriptors:
  - behavior: MEASURE
    timeout: 10
    recurrent: no
    arguments:
      - argument: DEPTH
        allowed_values: [0, 100]
      - argument: UNIT
        allowed_values: [C, F]
capability_descriptors: []
"""


def test_the_names_a_hook_reads_are_found_in_the_ast(tmp_path: Path) -> None:
    source = tmp_path / "measure.py"
    source.write_text(BEHAVIOR)
    read = arguments_read(str(source), "Measure")
    assert read is not None
    assert (read.names, read.complete) == (("TEMPERATURE", "UNIT", "PRECISION"), True)
    source.write_text(BEHAVIOR.replace('args["TEMPERATURE"]', "args[self.key]"))
    assert arguments_read(str(source), "Measure").complete is False  # type: ignore[union-attr]
    source.write_text(BEHAVIOR.replace('args.get("UNIT", "C")', "configure(args)"))
    assert arguments_read(str(source), "Measure").complete is False  # type: ignore[union-attr]


def test_a_catalog_argument_the_code_does_not_read_is_an_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "measure.py").write_text(BEHAVIOR)
    (tmp_path / "catalog.yaml").write_text(CATALOG)
    (tmp_path / "mission.py").write_text(
        textwrap.dedent(
            """\
            from executive_engine_api import execute_behavior


            def runMission():
                execute_behavior('MEASURE', DEPTH=10, UNIT='C')
            """
        )
    )
    result = runner.invoke(
        app, ["verify", "catalog.yaml", "-b", "measure.py", "--min-severity", "info"]
    )
    assert result.exit_code == 1
    lines = result.output.splitlines()
    assert (
        "catalog.yaml:6:9: error AX903 MEASURE: argument DEPTH is not read by "
        "measure:Measure, which reads (in its code) TEMPERATURE, UNIT, PRECISION"
    ) in lines
    ax904 = {line.split(" argument ")[1].split(",")[0] for line in lines if "AX904" in line}
    assert ax904 == {"TEMPERATURE", "PRECISION"}
    assert not [line for line in lines if "AX905" in line]
    # In flight: the behavior looks up TEMPERATURE, which no mission can pass.
    flown = runner.invoke(app, ["run", "mission.py", "-c", "catalog.yaml", "-b", "measure.py"])
    assert "PROCESS_FAILURE" in flown.output


def test_the_ast_is_read_not_run(tmp_path: Path) -> None:
    # A module that would fail when imported is still parsed for the names it reads.
    source = tmp_path / "broken.py"
    source.write_text("raise SystemExit('imported!')\n" + BEHAVIOR)
    read = arguments_read(str(source), "Measure")
    assert read is not None and "TEMPERATURE" in read.names
