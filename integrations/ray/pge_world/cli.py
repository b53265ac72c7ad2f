"""``pge-world SCRIPT --out DIR``: the console script.

Errors the user can fix (no cluster, another world in DIR, a script without ``tile``, a
script error in a tile, no ``pge`` on a worker) end with one line on stderr and exit
status 1; usage errors exit 2 (argparse). The run itself is :func:`pge_world.world.grow`.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Sequence

from .args import Options, parse
from .errors import WorldError
from .world import grow


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line ``argv``: exit status 0, 1 (a problem to fix) or 2 (usage)."""
    status = run(parse(argv))
    if "ray" in sys.modules and argv is None:
        # Connected to a cluster: everything is written (the manifest atomically), and
        # Ray's own shutdown at exit (disconnecting the job, which the cluster notices
        # anyway) takes most of a second. Leave at once.
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(status)
    return status


def run(options: Options) -> int:
    """:func:`~pge_world.world.grow` with its errors as one line on stderr: the exit status."""
    try:
        return grow(options)
    except WorldError as e:
        sys.stderr.write(f"pge-world: {e}\n")
        return 1
    except OSError as e:  # writing the world: a full disk, a file where DIR should be
        where = f"{e.filename}: " if e.filename else ""
        sys.stderr.write(f"pge-world: {where}{e.strerror or e}\n")
        return 1
    except KeyboardInterrupt:
        sys.stderr.write("pge-world: interrupted; run again on the same --out to resume\n")
        return 130


if __name__ == "__main__":
    sys.exit(main())
