"""Tiles on a worker: ONE ``pge run SCRIPT --tile I,J --tile ...`` for a batch of tiles.

It reports their hashes, instance counts and (without a shared folder) bytes.

This module imports nothing from Ray nor from the rest of the package: a Ray task takes it
by value (workers need Ray and ``pge``, not this package), and the same function runs in a
test or by hand.
"""

from __future__ import annotations

import getpass
import hashlib
import json
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TypedDict


class TileFailed(Exception):
    """A tile that fails for good (a script error, no ``pge`` on the worker).

    Retrying it would fail again, so the run stops with this message.
    """


class _GrownTile(TypedDict):
    i: int
    j: int
    sha256: str
    bytes: int
    instances: int


class GrownTile(_GrownTile, total=False):
    """A tile a batch grew: its index, hash, length, instances; ``glb``: its bytes.

    The bytes are sent back only when the worker does not see the world directory.
    """

    glb: bytes


class BatchResult(TypedDict):
    """What a batch task returns: where it ran, its time in the task, its tiles."""

    node: str
    seconds: float
    tiles: list[GrownTile]


def _prctl() -> Callable[..., int] | None:
    """Libc's prctl, resolved in the parent: the child before exec should do little."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        import ctypes

        prctl: Callable[..., int] = ctypes.CDLL("libc.so.6", use_errno=True).prctl
    except (OSError, AttributeError):
        return None
    return prctl


def _die_with_parent() -> Callable[[], object] | None:
    """Return a ``preexec_fn`` that has the child killed when the worker that started it dies.

    So a killed worker leaves no ``pge`` running on (Linux); None where that cannot be done.
    """
    prctl = _prctl()
    if prctl is None:
        return None
    return lambda: prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG


def last_line(text: str) -> str:
    """Return the last non-empty line of ``text`` (pge prints its error as one line)."""
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    return lines[-1] if lines else ""


def pge_args(
    script: Path,
    seed: int,
    overrides: Sequence[tuple[str, str]],
    time_limit: float | None = None,
) -> list[str]:
    """Return the arguments every ``pge`` call of a world shares: script, seed, --set values."""
    args = [str(script), "--seed", str(seed)]
    for name, value in overrides:
        args += ["--set", f"{name}={value}"]
    if time_limit is not None:
        args += ["--time-limit", str(time_limit)]
    return args


def default_variant_cache() -> Path:
    """Return this machine's variant cache: a folder of the user's in the temporary folder.

    The tiles that run on one machine then grow each species variant once.
    """
    try:
        user = getpass.getuser()
    except (KeyError, OSError):
        user = "user"
    return Path(tempfile.gettempdir()) / f"pge-variants-{user}"


def instances_by_tile(stats: str) -> dict[tuple[int, int], int]:
    """Return each tile's instance count from pge's ``--stats`` lines (a JSON object a tile)."""
    counts = {}
    for line in stats.splitlines():
        if line.strip():
            s = json.loads(line)
            i, j = s["tile"]
            counts[(i, j)] = int(s.get("instances", 0))
    return counts


class TileJob(TypedDict):
    """What every batch of a world shares: how to run ``pge`` and where the tiles go.

    ``program`` is a name looked up on the worker's PATH, or a path; ``threads`` pge's
    ``--threads``; ``shared``: the tiles refer to the world's shared variants
    (``../variants.bin``) rather than carry them. ``variant_cache`` (standalone tiles) is
    pge's ``--variant-cache`` folder: ``""`` for the worker machine's own
    (:func:`default_variant_cache`), None for none. ``out`` is the world directory when the
    worker sees it (the driver's machine, or a shared folder), else None.
    """

    program: str
    script: Path
    seed: int
    overrides: Sequence[tuple[str, str]]
    threads: int
    time_limit: float | None
    variant_cache: str | None
    shared: bool
    out: Path | None


def grow_tiles(
    job: TileJob, tiles: Sequence[tuple[int, int]], description: bytes | None
) -> BatchResult:
    """Grow the tiles ``[(i, j), ...]`` with ONE ``pge run SCRIPT --tile I,J ... --out-dir D``.

    The script's engine and the variants' description are read once for the batch; each
    file is the one ``pge run --tile I,J`` writes. Each tile's entry carries ``"glb"`` (its
    bytes) unless the job has an ``out``.

    With ``out`` pge writes the tiles into ``out/tiles/`` itself (each file atomically) and
    reads the shared variants' description there; nothing but hashes travels back. Without
    it the tiles are written into a scratch folder laid out as the world directory and
    their bytes are returned; shared variants then need ``description`` (the bytes of
    ``variants.json``, written into the scratch folder: the worker needs neither the binary
    file nor a shared folder).

    Raises :class:`TileFailed` when the program is missing, ``out`` is not on this machine,
    or ``pge`` exits with an error (its one line: ``tile I,J: FILE:LINE: message``).
    """
    program, out, shared = job["program"], job["out"], job["shared"]
    start = time.monotonic()
    exe = shutil.which(program)
    host = socket.gethostname()
    if exe is None:
        raise TileFailed(
            f"no `{program}` program on the PATH of the worker on {host}: "
            "install pge there, or pass --pge with its path on the workers"
        )
    if out is not None and not (out / "tiles").is_dir():
        raise TileFailed(
            f"the world directory {out} is not on the worker on {host}: run pge-world with "
            "--no-shared-fs, or on a folder every machine shares"
        )
    with tempfile.TemporaryDirectory(prefix="pge-tile-") as scratch:
        world = out if out is not None else Path(scratch)
        folder = world / "tiles"
        shared_args = pge_args(job["script"], job["seed"], job["overrides"], job["time_limit"])
        cmd = [exe, "run", *shared_args]
        for i, j in tiles:
            cmd += ["--tile", f"{i},{j}"]
        cmd += ["--out-dir", str(folder), "-q", "--stats", "--threads", str(job["threads"])]
        if shared:
            if out is None:
                folder.mkdir()
                (world / "variants.json").write_bytes(description or b"")
            cmd += ["--variants", str(world)]
        else:
            cache = job["variant_cache"]
            if cache == "":
                cache = str(default_variant_cache())
            if cache is not None:
                cmd += ["--variant-cache", cache]
            folder.mkdir(parents=True, exist_ok=True)
        proc = subprocess.run(
            cmd,
            stdin=subprocess.DEVNULL,
            capture_output=True,
            text=True,
            preexec_fn=_die_with_parent(),
        )
        if proc.returncode != 0:
            message = last_line(proc.stderr) or f"pge exited with status {proc.returncode}"
            raise TileFailed(message)
        try:
            instances = instances_by_tile(proc.stdout)
            grown: list[GrownTile] = []
            for i, j in tiles:
                data = (folder / f"{i}_{j}.glb").read_bytes()
                entry: GrownTile = {
                    "i": i,
                    "j": j,
                    "sha256": hashlib.sha256(data).hexdigest(),
                    "bytes": len(data),
                    "instances": instances[(i, j)],
                }
                if out is None:
                    entry["glb"] = data
                grown.append(entry)
        except (OSError, ValueError, KeyError, TypeError) as e:
            raise TileFailed(f"pge wrote no tile on {host}: {e}") from e
    return {"node": host, "seconds": time.monotonic() - start, "tiles": grown}
