"""Planning the work: the tiles ``pge tiles`` lists, cut into batches (one task each)."""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from numbers import Real
from typing import Any, TypeVar

from .errors import WorldError
from .records import Tile

#: The most tiles a task grows by default: enough to spread pge's start over many tiles, few
#: enough that progress, load balance and a retried task stay fine-grained on a small
#: cluster.
MAX_TILES_PER_TASK = 16

T = TypeVar("T")


def parse_tiles(text: str, script: str) -> list[Tile]:
    """Return the tiles in the output of ``pge tiles SCRIPT`` (a JSON list of tiles).

    Raises :class:`~pge_world.errors.WorldError` when it is not a list of tiles or the list
    is empty.
    """
    try:
        listed = json.loads(text)
    except ValueError as e:
        raise WorldError(f"pge tiles printed no tile list: {e}") from e
    if not isinstance(listed, list):
        raise WorldError("pge tiles printed no tile list: not a JSON list")
    tiles = []
    for n, t in enumerate(listed):
        if not _is_tile(t):
            raise WorldError(f"pge tiles printed no tile list: entry {n} is not a tile: {t}")
        tiles.append(Tile(i=t["i"], j=t["j"], min=list(t["min"]), max=list(t["max"])))
    if not tiles:
        raise WorldError(f"{script}: the forest has no tiles")
    return tiles


def _is_tile(t: Any) -> bool:
    """Whether ``t`` (parsed JSON) has integer ``i``, ``j`` and 2-number ``min``, ``max``."""

    def point(p: Any) -> bool:
        return (
            isinstance(p, list)
            and len(p) == 2
            and all(isinstance(x, Real) and not isinstance(x, bool) for x in p)
        )

    return (
        isinstance(t, dict)
        and all(isinstance(t.get(k), int) and not isinstance(t.get(k), bool) for k in "ij")
        and point(t.get("min"))
        and point(t.get("max"))
    )


def slots(cpus: Iterable[int], cpus_per_tile: int) -> int:
    """Return the tasks a cluster runs at once: each node's CPUs over the CPUs a task reserves."""
    return sum(n // cpus_per_tile for n in cpus)


def batches_of(todo: Sequence[T], slots: int, per_task: int) -> list[list[T]]:
    """Return the tiles to grow cut into batches, one task each.

    ``per_task`` tiles a batch; or (0) one batch per CPU slot, balanced, but no more than
    :data:`MAX_TILES_PER_TASK` tiles a batch. The tiles are dealt in turn, so neighbouring
    tiles (similar work) land in different batches.
    """
    if per_task > 0:
        count = -(-len(todo) // per_task)
    else:
        count = max(slots, -(-len(todo) // MAX_TILES_PER_TASK), 1)
    count = min(count, len(todo))
    return [list(todo[k::count]) for k in range(count)]
