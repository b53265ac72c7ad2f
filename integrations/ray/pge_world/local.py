"""The ``pge`` processes the driver runs on this machine, while Ray connects.

``pge tiles SCRIPT`` lists the tiles; ``pge run SCRIPT --variants-out DIR`` writes the
shared variants on every core.
"""

from __future__ import annotations

import subprocess
from collections.abc import Sequence
from pathlib import Path

from .errors import WorldError
from .plan import parse_tiles
from .records import Tile
from .tile import last_line, pge_args


def start_tile_list(
    program: str, script: Path, seed: int, overrides: Sequence[tuple[str, str]]
) -> subprocess.Popen[str]:
    """Start ``pge tiles SCRIPT`` (:func:`tile_list` reads it)."""
    try:
        return subprocess.Popen(
            [program, "tiles", *pge_args(script, seed, overrides)],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
    except OSError as e:
        raise WorldError(f"cannot run {program}: {e}") from e


def tile_list(lister: subprocess.Popen[str], script: Path) -> list[Tile]:
    """Return the tiles ``pge tiles`` printed, or its error line."""
    stdout, stderr = lister.communicate()
    if lister.returncode != 0:
        raise WorldError(last_line(stderr) or f"pge tiles exited with {lister.returncode}")
    return parse_tiles(stdout, str(script))


def start_variants(
    program: str,
    script: Path,
    seed: int,
    overrides: Sequence[tuple[str, str]],
    time_limit: float | None,
    out: Path,
) -> subprocess.Popen[str]:
    """Start ``pge run SCRIPT --variants-out DIR`` (every core of this machine)."""
    cmd = [program, "run", *pge_args(script, seed, overrides, time_limit)]
    cmd += ["--variants-out", str(out), "-q"]
    try:
        return subprocess.Popen(
            cmd,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
    except OSError as e:
        raise WorldError(f"cannot run {program}: {e}") from e


def finish_variants(writer: subprocess.Popen[str]) -> None:
    """Wait for :func:`start_variants`.

    Raises :class:`~pge_world.errors.WorldError` with pge's error line when it failed.
    """
    _, err = writer.communicate()
    if writer.returncode != 0:
        message = last_line(err) or f"pge exited with status {writer.returncode}"
        raise WorldError(f"variants: {message}")


def stop(processes: Sequence[subprocess.Popen[str] | None]) -> None:
    """Kill and reap the processes still running (a run that failed)."""
    for proc in processes:
        if proc is not None and proc.poll() is None:
            proc.kill()
            proc.wait()
