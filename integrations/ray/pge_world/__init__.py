"""pge-world: grow a PGE forest world tile by tile, in batches of tiles, one Ray
task each.

The command line is :func:`pge_world.cli.main`; the manifest format is in
:mod:`pge_world.manifest`.
"""

__version__ = "0.1.0"
