"""`aeroexec catalog ...` (placeholder until `catalog show` lands)."""

from __future__ import annotations

import typer

from aeroexec.cli.app import app

catalog_app = typer.Typer(help="Inspect behavior catalogs.", no_args_is_help=True)
app.add_typer(catalog_app, name="catalog")
