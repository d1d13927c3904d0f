"""`aeroexec layout --foxglove [--for REC] -o FILE`: the Foxglove/Lichtblick layout for
recordings (the generic one, or one for what a recording holds)."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Annotated

import typer

from aeroexec.cli.app import app, guarded
from aeroexec.cli.options import output_option
from aeroexec.errors import AeroexecError, Mark, RecordingError
from aeroexec.viz.foxglove_layout import content_for, generic_content, layout_text
from aeroexec.viz.view import open_session


def _write_whole(path: Path, text: str) -> None:
    """Write `text` to `path` whole or not at all (a temporary name, then a rename)."""
    where = Mark(str(path))
    if path.is_dir():
        raise RecordingError("is a directory; give a file name ending in .json", where)
    folder = path.parent if str(path.parent) else Path(".")
    try:
        descriptor, temporary = tempfile.mkstemp(prefix=f".{path.name}.", dir=folder)
    except OSError as exc:
        raise RecordingError(f"cannot write: {exc.strerror or exc}", where) from None
    try:
        with os.fdopen(descriptor, "w", encoding="utf-8") as stream:
            stream.write(text)
        os.chmod(temporary, 0o644)
        os.replace(temporary, path)
    except OSError as exc:
        Path(temporary).unlink(missing_ok=True)
        raise RecordingError(f"cannot write: {exc.strerror or exc}", where) from None
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


@app.command("layout")
@guarded
def layout(
    foxglove: Annotated[
        bool,
        typer.Option(
            "--foxglove", help="A layout for Foxglove (and Lichtblick, its open-source fork)."
        ),
    ] = False,
    output: Path | None = output_option("Write the layout here (default: standard output)."),
    drone: Annotated[
        str,
        typer.Option(
            "--drone",
            metavar="NAME",
            help="The drone's namespace in the recordings.",
            show_default=True,
        ),
    ] = "drone1",
    recording: Annotated[
        Path | None,
        typer.Option(
            "--for",
            metavar="REC",
            help="A layout for what this recording holds (its drone, log channels, "
            "capabilities), instead of the generic one for `run`'s sessions.",
        ),
    ] = None,
) -> None:
    """Write a viewer layout for aeroexec recordings, to import once: the flight in 3D
    (the world's markers and object, the vehicle on its frame), the plot of position and
    battery, the behavior events, the capabilities' transitions (one timeline each), the
    call log and the session's log.

    The generic layout fits `aeroexec run`'s sessions. A flight, an open-loop replay or
    an import has no session log (an import may have its bag's rosout, and no calls):
    `--for REC` writes the layout for what REC holds, leaving out what it lacks.

    Import it from the viewer's layout browser, "Import from file...", and pick the
    file: in Lichtblick the Layouts tab of the left sidebar (its app menu's "Import
    layout from file..." does nothing in the web app); in Foxglove the layout menu of
    the top bar (older versions: the Layouts tab).

    \b
    Examples:
      aeroexec layout --foxglove -o aeroexec-layout.json
      aeroexec layout --foxglove --drone drone2 > drone2.json
      aeroexec layout --foxglove --for flight.mcap -o flight-layout.json

    Exit codes: 0 written; 2 no viewer chosen, REC unreadable or not an aeroexec
    recording, or the file cannot be written.
    """
    if not foxglove:
        raise AeroexecError("choose the viewer the layout is for: --foxglove")
    if not drone.strip("/") or "/" in drone.strip("/"):
        raise AeroexecError(f"--drone: a namespace is one name, got '{drone}'")
    if recording is not None:
        content = content_for(open_session(recording))
    else:
        content = generic_content(drone.strip("/"))
    text = layout_text(content)
    if output is None:
        typer.echo(text, nl=False)
        return
    _write_whole(output, text)
    typer.echo(f"wrote {output}", err=True)
