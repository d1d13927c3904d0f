"""Where the example missions shipped with aeroexec live."""

from __future__ import annotations

from aeroexec.catalog.paths import DATA_DIR

APPENDIX_C = DATA_DIR / "missions" / "appendix_c.py"
