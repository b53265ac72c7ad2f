"""Tiles on a worker: ONE ``pge run SCRIPT --tile I,J --tile ...`` for a batch of tiles.

It reports the tiles grown and (without a shared folder) their bytes; the driver records
them with ``pge world add``, which reads and hashes each file.

This module imports nothing from Ray nor from the rest of the package: a Ray task takes it
by value (workers need Ray and ``pge``, not this package), and the same function runs in a
test or by hand.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import socket
import stat
import subprocess
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TypedDict


class TileFailed(Exception):
    """A tile that fails for good (a script error, no ``pge`` on the worker).

    Retrying it would fail again, so the run stops with this message.
    """


class _GrownTile(TypedDict):
    i: int
    j: int


class GrownTile(_GrownTile, total=False):
    """A tile a batch grew: its index; ``glb``: its bytes.

    The bytes are sent back only when the worker does not see the world directory.
    """

    glb: bytes


class BatchResult(TypedDict):
    """What a batch task returns: where it ran, its time in the task, its tiles."""

    node: str
    seconds: float
    tiles: list[GrownTile]


def die_with_parent() -> list[str]:
    """Return the command prefix that has ``pge`` killed when the worker that started it dies.

    ``setpriv --pdeathsig KILL`` (util-linux) where it is on the PATH, so a killed worker
    leaves no ``pge`` running; nothing elsewhere. (A ``preexec_fn`` would do the same from
    Python, but runs Python code between fork and exec: unsafe in Ray's multi-threaded
    worker.)
    """
    setpriv = shutil.which("setpriv")
    return [setpriv, "--pdeathsig", "KILL", "--"] if setpriv is not None else []


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
    """Return this machine's variant cache: a private folder of the user's in the temp folder.

    The tiles that run on one machine then grow each species variant once. Its name holds
    the user's id; :func:`private_folder` creates it 0700 and refuses one that another user
    could have planted or can write into.
    """
    return Path(tempfile.gettempdir()) / f"pge-variants-{os.getuid()}"


def private_folder(path: Path, uid: int | None = None) -> Path:
    """Create ``path`` mode 0700 if missing; return it once checked private to ``uid``.

    Raises :class:`TileFailed` when it is a link or not a folder, is owned by another user
    (default: this process's), or can be written by the group or others: a cache there
    could be read from or written to by someone else.
    """
    owner = os.getuid() if uid is None else uid
    with contextlib.suppress(FileExistsError):
        path.mkdir(mode=0o700)
    st = os.lstat(path)
    why = None
    if not stat.S_ISDIR(st.st_mode):
        why = "not a folder (a link, or a file)"
    elif st.st_uid != owner:
        why = f"owned by another user (uid {st.st_uid})"
    elif st.st_mode & 0o022:
        why = f"writable by others (mode {stat.S_IMODE(st.st_mode):o})"
    if why is not None:
        raise TileFailed(
            f"the variant cache {path} on {socket.gethostname()} is {why}: remove it, or pass "
            "--variant-cache with a folder of your own"
        )
    return path


class TileJob(TypedDict):
    """What every batch of a world shares: how to run ``pge`` and where the tiles go.

    ``program`` is a name looked up on the worker's PATH, or a path; ``threads`` pge's
    ``--threads``; ``shared``: the tiles refer to the world's shared variants
    (``../variants.bin``) rather than carry them. ``variant_cache`` (standalone tiles) is
    pge's ``--variant-cache`` folder: ``""`` for the worker machine's own
    (:func:`default_variant_cache`, checked private), None for none. ``out`` is the world
    directory when the worker sees it (the driver's machine, or a shared folder), else None.
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
    reads the shared variants' description there; nothing but the indices travels back. Without
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
        cmd += ["--out-dir", str(folder), "-q", "--threads", str(job["threads"])]
        if shared:
            if out is None:
                folder.mkdir()
                (world / "variants.json").write_bytes(description or b"")
            cmd += ["--variants", str(world)]
        else:
            cache = job["variant_cache"]
            if cache == "":
                cache = str(private_folder(default_variant_cache()))
            if cache is not None:
                cmd += ["--variant-cache", cache]
            folder.mkdir(parents=True, exist_ok=True)
        proc = subprocess.run(
            [*die_with_parent(), *cmd], stdin=subprocess.DEVNULL, capture_output=True, text=True
        )
        if proc.returncode != 0:
            message = last_line(proc.stderr) or f"pge exited with status {proc.returncode}"
            raise TileFailed(message)
        grown: list[GrownTile] = []
        for i, j in tiles:
            entry: GrownTile = {"i": i, "j": j}
            path = folder / f"{i}_{j}.glb"
            try:
                if out is None:
                    entry["glb"] = path.read_bytes()
                elif not path.is_file():
                    raise OSError(f"no {path}")
            except OSError as e:
                raise TileFailed(f"pge wrote no tile {i},{j} on {host}: {e}") from e
            grown.append(entry)
    return {"node": host, "seconds": time.monotonic() - start, "tiles": grown}
