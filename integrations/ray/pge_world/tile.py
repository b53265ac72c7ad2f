"""One tile on a worker: ``pge run SCRIPT --tile I,J``, its bytes and instance count.

This module imports nothing from Ray, so the same function runs in a Ray task, in a test, or
by hand.
"""

import getpass
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile


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


def grow_tile(
    program, script, seed, overrides, i, j, threads=1, time_limit=None, variant_cache="",
    variants=None,
):
    """Runs ``pge run SCRIPT --tile I,J`` with ``program`` (a name looked up on this
    machine's PATH, or a path) and returns ``{"glb": bytes, "instances": n, "node": host}``.

    ``variant_cache`` is pge's ``--variant-cache`` folder: ``""`` for this machine's own
    (:func:`default_variant_cache`), None for none.

    ``variants`` is the world's shared variants description (the bytes of
    ``variants.json``), or None for a standalone tile. The tile then refers to the variants
    instead of carrying them: the description is written into a scratch folder laid out as
    the world directory (``variants.json`` beside ``tiles/``), so the tile's reference is
    ``../variants.bin`` as in the world; the worker needs neither the binary file nor a
    shared folder.

    Raises :class:`TileFailed` when ``program`` is missing or ``pge`` exits with an error.
    """
    exe = shutil.which(program)
    host = socket.gethostname()
    if exe is None:
        raise TileFailed(
            f"no `{program}` program on the PATH of the worker on {host}: "
            "install pge there, or pass --pge with its path on the workers"
        )
    with tempfile.TemporaryDirectory(prefix="pge-tile-") as folder:
        os.mkdir(os.path.join(folder, "tiles"))
        out = os.path.join(folder, "tiles", f"{i}_{j}.glb")
        cmd = [exe, "run"] + pge_args(script, seed, overrides, time_limit)
        cmd += ["--tile", f"{i},{j}", "-o", out, "-q", "--stats", "--threads", str(threads)]
        if variants is not None:
            with open(os.path.join(folder, "variants.json"), "wb") as f:
                f.write(variants)
            cmd += ["--variants", folder]
        else:
            if variant_cache == "":
                variant_cache = default_variant_cache()
            if variant_cache is not None:
                cmd += ["--variant-cache", variant_cache]
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
            stats = json.loads(last_line(proc.stdout))
            with open(out, "rb") as f:
                glb = f.read()
        except (OSError, ValueError) as e:
            raise TileFailed(f"pge wrote no tile on {host}: {e}") from e
    return {"glb": glb, "instances": int(stats.get("instances", 0)), "node": host}
