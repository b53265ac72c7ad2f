"""PGE, the procedural generation engine, as a Python module.

A Lua script and its parameters in, the ``.glb`` bytes ``pge run`` writes out::

    import pge

    result = pge.generate("scripts/species/oak.lua", params={"height": 4}, seed=7)
    open("oak.glb", "wb").write(result.glb)
    print(result.stats["triangles"], result.warnings)

Generating releases the GIL (other Python threads run meanwhile) and Ctrl-C
(``KeyboardInterrupt``) stops a run within a fraction of a second. Scripts find the script
library as ``pge run`` does: ``$PGE_LIBRARY``, else a ``scripts/`` folder holding a
``.pge-library`` file in the current folder or one above it.
"""

from __future__ import annotations

import json
import os
from typing import Any, Optional, Union

from . import _pge

__all__ = [
    "InstructionLimit",
    "MemoryLimit",
    "Result",
    "ScriptError",
    "TimeLimit",
    "generate",
    "library",
    "params",
    "tiles",
    "version",
]

#: The version of PGE this module runs.
version: str = _pge.version

Path = Union[str, "os.PathLike[str]"]


class ScriptError(Exception):
    """A script failed: ``str(e)`` is ``FILE:LINE: message``, as ``pge run`` prints it.

    ``file`` is the script to fix (as given, or a module it loaded), ``line`` its 1-based
    line (``None`` when unknown, e.g. a file that cannot be read), ``message`` what went
    wrong.
    """

    def __init__(self, message: str, file: Optional[str] = None, line: Optional[int] = None):
        super().__init__(message, file, line)
        self.message = message
        self.file = file
        self.line = line

    def __str__(self) -> str:
        if self.file is None:
            return self.message
        if self.line is None:
            return f"{self.file}: {self.message}"
        return f"{self.file}:{self.line}: {self.message}"


class TimeLimit(ScriptError):
    """The run went past ``time_limit`` seconds; ``file:line`` is where it was."""


class MemoryLimit(ScriptError):
    """The run went past ``memory_limit`` MiB."""


class InstructionLimit(ScriptError):
    """The script's Lua code went past its instruction budget."""


class Result:
    """What :func:`generate` returns.

    ``glb``: the ``.glb`` file (bytes), exactly what ``pge run`` writes for the same
    arguments; ``stats``: what ``pge run --stats`` prints (a dict, without ``output``);
    ``warnings``: the run's warnings (``FILE:LINE: warning: ...``); ``files``: every file
    the run read (the script, the modules it required, meshes, textures), to watch.
    """

    __slots__ = ("files", "glb", "stats", "warnings")

    def __init__(
        self, glb: bytes, stats: dict[str, Any], warnings: list[str], files: list[str]
    ):
        self.glb = glb
        self.stats = stats
        self.warnings = warnings
        self.files = files

    def __repr__(self) -> str:
        return (
            f"<pge.Result {len(self.glb)} bytes, {self.stats.get('triangles')} triangles, "
            f"{len(self.warnings)} warnings>"
        )


def generate(
    script: Optional[Path] = None,
    *,
    source: Optional[str] = None,
    name: Optional[str] = None,
    params: Optional[dict[str, Union[bool, int, float, str]]] = None,
    seed: int = 1,
    steps: Optional[int] = None,
    stages: Optional[list[int]] = None,
    threads: Optional[int] = None,
    time_limit: float = 300,
    memory_limit: int = 4096,
) -> Result:
    """Run a script and grow its model: ``pge run SCRIPT`` with the same arguments.

    ``script`` is the path of a Lua script; or give its text as ``source=`` with ``name=``
    the file it is shown as in errors (its folder, when it exists, is where ``require``
    looks). ``params`` overrides the parameters the script declares (``--set``), ``seed``
    seeds every random draw, ``steps`` replaces the algorithm's step count, ``stages``
    (increasing step counts) writes one scene per growth stage, ``threads`` sizes the pool
    of parallel work (default: every core; the bytes are the same for any count),
    ``time_limit`` (seconds) and ``memory_limit`` (MiB) bound the run.

    Raises :class:`ScriptError` (or :class:`TimeLimit`, :class:`MemoryLimit`,
    :class:`InstructionLimit`) for a failing script, ``TypeError``/``ValueError`` for bad
    arguments, ``KeyboardInterrupt`` when interrupted.
    """
    glb, stats, warnings, files = _pge.generate(
        script,
        source=source,
        name=name,
        params=params,
        seed=seed,
        steps=steps,
        stages=stages,
        threads=threads,
        time_limit=time_limit,
        memory_limit=memory_limit,
    )
    return Result(glb, json.loads(stats), warnings, [str(f) for f in files])


def library() -> Optional[str]:
    """The script library's folder as ``pge run`` finds it (see the module's doc), or None."""
    found = _pge.library()
    return None if found is None else str(found)


def params(
    script: Optional[Path] = None,
    *,
    source: Optional[str] = None,
    name: Optional[str] = None,
) -> dict[str, dict[str, Any]]:
    """The parameters a script declares with ``pge.params``, by name.

    ``{name: {"default": ..., "min": ..., "max": ..., "doc": ...}}`` (``min``, ``max`` and
    ``doc`` are ``None`` when not declared). The script runs (it declares them), its
    algorithm does not grow.
    """
    return _pge.params(script, source=source, name=name)


def tiles(
    script: Optional[Path] = None,
    *,
    source: Optional[str] = None,
    name: Optional[str] = None,
    params: Optional[dict[str, Union[bool, int, float, str]]] = None,
    seed: int = 1,
) -> list[dict[str, Any]]:
    """The tiles of a forest with ``tile = T`` (``pge tiles``).

    ``[{"i": I, "j": J, "min": (x, z), "max": (x, z)}, ...]``: I along x, J along z, from 0
    at the -x, -z corner. A script that returns no tiled forest raises :class:`ScriptError`.
    """
    return _pge.tiles(script, source=source, name=name, params=params, seed=seed)
