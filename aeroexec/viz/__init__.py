"""Views of aeroexec recordings: Rerun (`aeroexec view`) and Foxglove (`aeroexec layout`).

- `write_view` (view.py): one recording, or two side by side, into an `.rrd` file;
- `Layout` (layout.py): the entity tree, the one place paths are defined;
- `SessionConverter` (convert.py): records to rows, streaming;
- `build_blueprint` (blueprint.py): the layout the viewer opens on;
- viewer.py: finding and starting the Rerun viewer;
- foxglove_layout.py: the Foxglove/Lichtblick layout for aeroexec recordings.

The names below are imported on first use: rerun takes about half a second to import,
and viewer.py and foxglove_layout.py need none of it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from aeroexec.lazy import lazy_exports

if TYPE_CHECKING:
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

_HOMES = {
    "build_blueprint": "blueprint",
    "ConvertStats": "convert",
    "SessionConverter": "convert",
    "DIFF_ROOTS": "layout",
    "Layout": "layout",
    "layouts_for": "layout",
    "APPLICATION_ID": "view",
    "SourceReport": "view",
    "ViewReport": "view",
    "default_output": "view",
    "open_session": "view",
    "recording_id_for": "view",
    "write_view": "view",
}


__getattr__, __dir__ = lazy_exports(__name__, _HOMES, globals())


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
