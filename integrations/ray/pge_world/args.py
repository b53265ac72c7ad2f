"""The command line of ``pge-world``: parsed into :class:`Options`.

Usage errors (an unknown flag, a ``--set`` that is not NAME=VALUE, no ``--out``) exit with
status 2 (argparse); :meth:`Options.check` turns numbers out of range into a
:class:`~pge_world.errors.WorldError` (status 1).
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from dataclasses import dataclass

from .errors import WorldError


def parse_set(text: str) -> tuple[str, str]:
    """``NAME=VALUE`` as a pair (an argparse type)."""
    name, sep, value = text.partition("=")
    if not sep or not name.strip():
        raise argparse.ArgumentTypeError(f"'{text}' is not NAME=VALUE")
    return (name.strip(), value)


def parser() -> argparse.ArgumentParser:
    """Return the command line of ``pge-world``."""
    p = argparse.ArgumentParser(
        prog="pge-world",
        description="Grow a PGE forest (a script with tile = T) tile by tile on a Ray "
        "cluster, in batches (one task and one pge process each), written to "
        "DIR/tiles/I_J.glb with the manifest "
        "DIR/world.json. Running again on the same DIR resumes: tiles already written "
        "are skipped.",
    )
    p.add_argument("script", help="the forest script (pge.Forest with tile = T)")
    p.add_argument("--out", required=True, metavar="DIR", help="the world directory")
    p.add_argument(
        "--address",
        metavar="ADDR",
        help="the Ray cluster (HOST:PORT of its head, or 'auto'); default: the cluster "
        "started on this machine with `ray start`, else a new one on this machine",
    )
    p.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        type=parse_set,
        metavar="NAME=VALUE",
        help="override a parameter declared with pge.params (repeatable)",
    )
    p.add_argument("--seed", type=int, default=1, help="seed of every random draw (default 1)")
    p.add_argument(
        "--pge",
        default="pge",
        metavar="PROGRAM",
        help="the pge program: a name looked up on the PATH (here and on every worker) "
        "or a path that exists on every machine (default: pge)",
    )
    p.add_argument(
        "--cpus-per-tile",
        type=int,
        default=1,
        metavar="N",
        help="CPUs each tile task reserves and pge threads it uses (default 1)",
    )
    p.add_argument(
        "--retries",
        type=int,
        default=3,
        metavar="N",
        help="times a tile is run again after its worker or machine died (default 3)",
    )
    p.add_argument(
        "--time-limit",
        type=float,
        metavar="SECONDS",
        help="pge's --time-limit for every tile (default: pge's own)",
    )
    p.add_argument(
        "--standalone-tiles",
        action="store_true",
        help="every tile carries the variant meshes it places (a glb of its own, ~30 MB for "
        "big.lua) instead of referring to DIR/variants.bin, the variants written once on this "
        "machine (the default)",
    )
    p.add_argument(
        "--variant-cache",
        default="",
        metavar="DIR",
        help="with --standalone-tiles, pge's --variant-cache on every worker: the folder where "
        "the tiles of a machine share the species variants they grow (a path that exists on "
        "every machine, local or shared); default: pge-variants-USER in each machine's "
        "temporary folder",
    )
    p.add_argument(
        "--no-variant-cache",
        action="store_true",
        help="every tile grows every variant itself",
    )
    p.add_argument(
        "--adopt",
        action="store_true",
        help="take tile files already in DIR/tiles that the manifest does not list (written "
        "by a Kubernetes Indexed Job or a Slurm array) when their seed, parameters and tile "
        "index match this run",
    )
    p.add_argument(
        "--shared-fs",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="the workers see DIR at the same path (one machine, or a shared folder): the "
        "tasks write the tiles there themselves and return only their hashes, instead of "
        "sending the bytes to this machine; default: on when every node of the cluster is "
        "this machine",
    )
    p.add_argument(
        "--tiles-per-task",
        type=int,
        default=0,
        metavar="N",
        help="tiles one task grows with one pge process (default: the tiles spread evenly "
        "over the cluster's CPUs, one task each, at most 16 tiles a task)",
    )
    p.add_argument(
        "--timings",
        action="store_true",
        help="print when each phase of the run ended, in seconds since this process started",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress")
    return p


@dataclass(frozen=True)
class Options:
    """A run's options, as the command line gave them (paths as typed)."""

    script: str
    out: str
    address: str | None = None
    overrides: tuple[tuple[str, str], ...] = ()
    seed: int = 1
    pge: str = "pge"
    cpus_per_tile: int = 1
    retries: int = 3
    time_limit: float | None = None
    standalone_tiles: bool = False
    variant_cache: str = ""
    no_variant_cache: bool = False
    adopt: bool = False
    shared_fs: bool | None = None
    tiles_per_task: int = 0
    timings: bool = False
    quiet: bool = False

    def check(self) -> None:
        """Refuse numbers out of range (a :class:`~pge_world.errors.WorldError`)."""
        if self.cpus_per_tile < 1 or self.retries < 0 or self.tiles_per_task < 0:
            raise WorldError(
                "--cpus-per-tile must be at least 1, --retries and --tiles-per-task at least 0"
            )


def parse(argv: Sequence[str] | None = None) -> Options:
    """Return the options of the command line ``argv`` (default: ``sys.argv[1:]``).

    A usage error prints argparse's message and exits with status 2.
    """
    ns = parser().parse_args(argv)
    return Options(
        script=ns.script,
        out=ns.out,
        address=ns.address,
        overrides=tuple(ns.overrides),
        seed=ns.seed,
        pge=ns.pge,
        cpus_per_tile=ns.cpus_per_tile,
        retries=ns.retries,
        time_limit=ns.time_limit,
        standalone_tiles=ns.standalone_tiles,
        variant_cache=ns.variant_cache,
        no_variant_cache=ns.no_variant_cache,
        adopt=ns.adopt,
        shared_fs=ns.shared_fs,
        tiles_per_task=ns.tiles_per_task,
        timings=ns.timings,
        quiet=ns.quiet,
    )
