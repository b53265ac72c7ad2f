"""pge-world: grow a PGE forest world tile by tile on a Ray cluster.

The tiles are grown in batches, one Ray task and one ``pge`` process each. The command line
is :func:`pge_world.cli.main`; the manifest format is in :mod:`pge_world.manifest`.
"""

import time

#: When the package was imported: the start of the run where the process's own start time
#: cannot be read (off Linux), for ``--timings``.
IMPORTED_AT = time.time()

__version__ = "0.1.0"
