"""The world directory and its manifest ``DIR/world.json``, through ``pge world``.

``pge world`` (Rust, docs/worlds.md) is the one writer of the manifest: it opens the
directory (refusing another world's, or a folder of other files), records the shared
variants and each tile written (checking it is this world's), adopts the tiles a job array
left, and marks the world complete. This module runs it on this machine and reads what it
prints; it also writes a tile sent back from a worker (atomically) before it is recorded.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import subprocess
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

from .errors import WorldError
from .records import TileKey, VariantsEntry

MANIFEST = "world.json"
VARIANTS_BIN = "variants.bin"
VARIANTS_JSON = "variants.json"


def tile_file(i: int, j: int) -> str:
    """Return the file of tile (i, j), relative to the world directory."""
    return f"tiles/{i}_{j}.glb"


def write_atomically(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file renamed over it.

    The temporary file is named as pge names its own (``.tmp*``), so ``pge world`` removes
    it when a killed process leaves it.
    """
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


@dataclass(frozen=True)
class Opened:
    """A world directory opened by ``pge world init``.

    ``created``: it did not exist; ``fresh``: it had no manifest (``init`` wrote a new one,
    with no tile); ``complete``: the manifest lists every tile, all intact;
    ``variants``: the shared variants it records are there unchanged; ``tiles``: the tiles
    kept (their files intact).
    """

    created: bool
    fresh: bool
    complete: bool
    variants: bool
    tiles: frozenset[TileKey]


def _pairs(value: Any) -> list[TileKey]:
    return [(int(i), int(j)) for i, j in value]


def _world(program: str, args: Sequence[str]) -> str:
    """Run ``pge world ARGS``: its standard output; its error line as a WorldError."""
    try:
        proc = subprocess.run(
            [program, "world", *args],
            stdin=subprocess.DEVNULL,
            capture_output=True,
            text=True,
        )
    except OSError as e:
        raise WorldError(f"cannot run {program}: {e}") from e
    if proc.returncode != 0:
        lines = [line.strip() for line in proc.stderr.splitlines() if line.strip()]
        raise WorldError(lines[-1] if lines else f"pge world exited with {proc.returncode}")
    return proc.stdout


def _json(program: str, args: Sequence[str]) -> Any:
    text = _world(program, args)
    try:
        return json.loads(text)
    except ValueError as e:
        raise WorldError(f"pge world {args[0]} printed no JSON ({e}): is pge too old?") from e


def init(
    program: str,
    script: Path,
    seed: int,
    overrides: Sequence[tuple[str, str]],
    out: Path,
    shared: bool,
) -> Opened:
    """Open ``out`` for the world of ``script``, ``seed`` and ``overrides`` (``pge world init``).

    Raises :class:`~pge_world.errors.WorldError` when it holds another world, is a folder of
    other files, or its manifest is not one.
    """
    args = ["init", str(script), "--out", str(out), "--seed", str(seed)]
    for name, value in overrides:
        args += ["--set", f"{name}={value}"]
    if not shared:
        args.append("--standalone-tiles")
    state = _json(program, args)
    return Opened(
        created=bool(state["created"]),
        fresh=bool(state["fresh"]),
        complete=bool(state["complete"]),
        variants=bool(state["variants"]),
        tiles=frozenset(_pairs(state["tiles"])),
    )


def forget(out: Path, opened: Opened) -> None:
    """Leave ``out`` as it was before a run that failed without recording a tile.

    A folder the run created is removed; a manifest it wrote into a folder without one is.
    """
    if opened.created:
        shutil.rmtree(out, ignore_errors=True)
    elif opened.fresh:
        with contextlib.suppress(OSError):
            (out / MANIFEST).unlink()


def record_variants(program: str, out: Path) -> tuple[bool, VariantsEntry]:
    """Record the shared variants written into ``out`` (``pge world variants``).

    Returns whether they differ from those recorded before (every tile then grows again)
    and their record.
    """
    state = _json(program, ["variants", str(out)])
    return bool(state["changed"]), cast(VariantsEntry, state["variants"])


def add(program: str, out: Path, tiles: Sequence[TileKey]) -> None:
    """Record the tiles written into ``out/tiles`` (``pge world add``)."""
    if tiles:
        _world(program, ["add", str(out), *(f"{i},{j}" for i, j in tiles)])


def adopt(program: str, out: Path) -> list[TileKey]:
    """Record the tile files in ``out/tiles`` the manifest did not list (``pge world adopt``)."""
    return _pairs(_json(program, ["adopt", str(out)]))


def finish(program: str, out: Path) -> int:
    """Mark the world complete (``pge world finish``): its instances."""
    return int(_json(program, ["finish", str(out)])["instances"])
