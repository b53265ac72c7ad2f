"""Tiles on a worker: one ``pge run SCRIPT --tile I,J --tile ...`` for a batch of tiles,
their hashes, instance counts and (without a shared folder) bytes.

This module imports nothing from Ray, so the same function runs in a Ray task, in a test, or
by hand.
"""

import getpass
import hashlib
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time


class TileFailed(Exception):
    """A tile that fails for good (a script error, no ``pge`` on the worker): retrying it
    would fail again, so the run stops with this message."""


def _prctl():
    """libc's prctl, resolved here in the parent: the child between fork and exec should do
    as little as it can."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        import ctypes

        return ctypes.CDLL("libc.so.6", use_errno=True).prctl
    except (OSError, AttributeError):
        return None


def _die_with_parent():
    """For ``preexec_fn``: the child is killed when the worker that started it dies (Linux),
    so a killed worker leaves no ``pge`` running on; None where that cannot be done."""
    prctl = _prctl()
    if prctl is None:
        return None
    return lambda: prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG


def last_line(text):
    """The last non-empty line of ``text`` (pge prints its error as one line)."""
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    return lines[-1] if lines else ""


def pge_args(script, seed, overrides, time_limit=None):
    """The arguments every ``pge`` call of a world shares: script, seed, --set values."""
    args = [script, "--seed", str(seed)]
    for name, value in overrides:
        args += ["--set", f"{name}={value}"]
    if time_limit is not None:
        args += ["--time-limit", str(time_limit)]
    return args


def default_variant_cache():
    """This machine's variant cache: a folder of the user's in the temporary folder, so the
    tiles that run on one machine grow each species variant once."""
    try:
        user = getpass.getuser()
    except (KeyError, OSError):
        user = "user"
    return os.path.join(tempfile.gettempdir(), f"pge-variants-{user}")


def grow_tiles(
    program, script, seed, overrides, tiles, threads=1, time_limit=None, variant_cache="",
    shared=False, description=None, out=None,
):
    """Grows the tiles ``[(i, j), ...]`` with ONE ``pge run SCRIPT --tile I,J --tile ...
    --out-dir D`` (the script's engine and the variants' description read once for the
    batch; each file is the one ``pge run --tile I,J`` writes) with ``program`` (a name
    looked up on this machine's PATH, or a path). Returns ``{"node": host, "seconds": s,
    "tiles": [{"i", "j", "sha256", "bytes", "instances"}, ...]}``, each tile's entry with
    ``"glb"`` (its bytes) unless ``out`` is given.

    ``out`` is the world directory when this worker sees it (the driver's machine, or a
    shared folder): pge writes the tiles into ``out/tiles/`` itself (each file atomically)
    and reads the shared variants' description there; nothing but hashes travels back.
    Without it the tiles are written into a scratch folder laid out as the world directory
    and their bytes are returned; shared variants then need ``description`` (the bytes of
    ``variants.json``, written into the scratch folder: the worker needs neither the binary
    file nor a shared folder).

    ``shared``: the tiles refer to the world's shared variants (``../variants.bin``) rather
    than carry them. ``variant_cache`` (standalone tiles) is pge's ``--variant-cache``
    folder: ``""`` for this machine's own (:func:`default_variant_cache`), None for none.

    Raises :class:`TileFailed` when ``program`` is missing, ``out`` is not on this machine,
    or ``pge`` exits with an error (its one line: ``tile I,J: FILE:LINE: message``).
    """
    start = time.monotonic()
    exe = shutil.which(program)
    host = socket.gethostname()
    if exe is None:
        raise TileFailed(
            f"no `{program}` program on the PATH of the worker on {host}: "
            "install pge there, or pass --pge with its path on the workers"
        )
    if out is not None and not os.path.isdir(os.path.join(out, "tiles")):
        raise TileFailed(
            f"the world directory {out} is not on the worker on {host}: run pge-world with "
            "--no-shared-fs, or on a folder every machine shares"
        )
    with tempfile.TemporaryDirectory(prefix="pge-tile-") as scratch:
        world = out if out is not None else scratch
        folder = os.path.join(world, "tiles")
        cmd = [exe, "run"] + pge_args(script, seed, overrides, time_limit)
        for i, j in tiles:
            cmd += ["--tile", f"{i},{j}"]
        cmd += ["--out-dir", folder, "-q", "--stats", "--threads", str(threads)]
        if shared:
            if out is None:
                os.mkdir(folder)
                with open(os.path.join(scratch, "variants.json"), "wb") as f:
                    f.write(description)
            cmd += ["--variants", world]
        else:
            if variant_cache == "":
                variant_cache = default_variant_cache()
            if variant_cache is not None:
                cmd += ["--variant-cache", variant_cache]
            os.makedirs(folder, exist_ok=True)
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
            stats = [json.loads(line) for line in proc.stdout.splitlines() if line.strip()]
            instances = {tuple(s["tile"]): int(s.get("instances", 0)) for s in stats}
            grown = []
            for i, j in tiles:
                with open(os.path.join(folder, f"{i}_{j}.glb"), "rb") as f:
                    data = f.read()
                entry = {
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
