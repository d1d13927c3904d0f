"""Rerun views of aeroexec recordings (`aeroexec view`).

- `write_view` (view.py): one recording, or two side by side, into an `.rrd` file;
- `Layout` (layout.py): the entity tree, the one place paths are defined;
- `SessionConverter` (convert.py): records to rows, streaming;
- `build_blueprint` (blueprint.py): the layout the viewer opens on;
- viewer.py: finding and starting the Rerun viewer.
"""

from __future__ import annotations

from aeroexec.viz.blueprint import build_blueprint
from aeroexec.viz.convert import ConvertStats, SessionConverter
from aeroexec.viz.layout import DIFF_ROOTS, Layout, layouts_for
from aeroexec.viz.view import (
    APPLICATION_ID,
    SourceReport,
    ViewReport,
    default_output,
    open_session,
    recording_id_for,
    write_view,
)

__all__ = [
    "APPLICATION_ID",
    "DIFF_ROOTS",
    "ConvertStats",
    "Layout",
    "SessionConverter",
    "SourceReport",
    "ViewReport",
    "build_blueprint",
    "default_output",
    "layouts_for",
    "open_session",
    "recording_id_for",
    "write_view",
]
