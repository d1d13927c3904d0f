"""The `aeroexec` command line (typer). Importing the command modules registers them."""

from __future__ import annotations

from aeroexec.cli import catalog_cmd  # noqa: F401  (registers `catalog`)
from aeroexec.cli import run_cmd  # noqa: F401  (registers `run`)
from aeroexec.cli import fly_cmd  # noqa: F401  (registers `fly`)
from aeroexec.cli import mavsim_cmd  # noqa: F401  (registers `mavsim`)
from aeroexec.cli import recording_cmd  # noqa: F401  (registers `info`, `recover`)
from aeroexec.cli import verify_cmd  # noqa: F401  (registers `verify`)
from aeroexec.cli import view_cmd  # noqa: F401  (registers `view`)
from aeroexec.cli import layout_cmd  # noqa: F401  (registers `layout`)
from aeroexec.cli import replay_cmd  # noqa: F401  (registers `replay`)
from aeroexec.cli import diff_cmd  # noqa: F401  (registers `diff`)
from aeroexec.cli import report_cmd  # noqa: F401  (registers `report merge`)
from aeroexec.cli import import_cmd  # noqa: F401  (registers `import`)
from aeroexec.cli import behaviors_cmd  # noqa: F401  (registers `behaviors`)
from aeroexec.cli.app import app


def main() -> None:
    app()


__all__ = ["app", "main"]
