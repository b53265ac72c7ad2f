"""Running on Ray: connecting, the cluster's nodes, the batch tasks and their results.

Ray is imported only when a run connects (importing it takes a second or more, which the
driver spends listing the tiles and writing the variants).
"""

from __future__ import annotations

import ipaddress
import os
import socket
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, NamedTuple

from .errors import WorldError
from .records import Tile
from .tile import BatchResult, TileFailed, TileJob, grow_tiles, last_line

if TYPE_CHECKING:
    from ray import ObjectRef


def reachable(address: str) -> None:
    """Fail at once when nothing listens at HOST:PORT (Ray itself would retry for minutes)."""
    host, sep, port = address.rpartition(":")
    if not sep or not port.isdigit():
        raise WorldError(f"--address {address} is not HOST:PORT (the head's GCS port, 6379)")
    host = host.removeprefix("ray://").strip("[]")
    try:
        socket.create_connection((host, int(port)), timeout=10).close()
    except OSError as e:
        raise WorldError(
            f"no Ray cluster at {address} ({e.strerror or e}); start one with "
            "`ray start --head` and pass its address with --address"
        ) from e


def init_options(address: str | None) -> dict[str, Any]:
    """Return the arguments of ``ray.init`` for the cluster at ``address``.

    None is this machine's cluster, or a new one. A cluster on this machine's loopback
    makes that address the driver's node.
    """
    kwargs: dict[str, Any] = {"logging_level": "ERROR", "log_to_driver": False}
    if address is None:
        kwargs["include_dashboard"] = False
        return kwargs
    kwargs["address"] = address
    host = address.rsplit(":", 1)[0] if ":" in address else address
    try:
        if ipaddress.ip_address(host).is_loopback:
            kwargs["_node_ip_address"] = host
    except ValueError:
        pass
    return kwargs


def connect(address: str | None) -> None:
    """Connect to the Ray cluster at ``address`` (None: this machine's), or say what to do."""
    if address is not None and address != "auto":
        reachable(address)
    import ray

    # The first failed tile ends the run; the others' errors are not news.
    os.environ.setdefault("RAY_IGNORE_UNHANDLED_ERRORS", "1")
    try:
        ray.init(**init_options(address))
    except Exception as e:  # Ray raises several types for an unreachable cluster.
        where = f"at {address}" if address else "on this machine"
        reason = last_line(str(e)) or type(e).__name__
        raise WorldError(
            f"no Ray cluster {where} ({reason}); start one with `ray start --head` "
            "and pass its address with --address"
        ) from e


class Node(NamedTuple):
    """A node of the cluster that has CPUs."""

    id: str
    address: str
    cpus: int


def nodes() -> tuple[list[Node], bool]:
    """Return the alive nodes that have CPUs, and whether they are all the driver's machine."""
    import ray

    here = ray.get_runtime_context().get_node_id()
    alive = [n for n in ray.nodes() if n.get("Alive")]
    mine = next((n["NodeManagerAddress"] for n in alive if n["NodeID"] == here), None)
    working = [
        Node(n["NodeID"], n["NodeManagerAddress"], int(n.get("Resources", {}).get("CPU", 0)))
        for n in alive
    ]
    working = [w for w in working if w.cpus > 0]
    return working, all(w.address == mine for w in working)


class Running:
    """The batch tasks in flight, each with its tiles."""

    def __init__(self, pending: dict[ObjectRef[BatchResult], list[Tile]]) -> None:
        """Track ``pending`` (a task's reference: its batch)."""
        self.pending = pending

    def __len__(self) -> int:
        """Return the tasks still running."""
        return len(self.pending)

    def wait(self, timeout: float = 1.0) -> list[tuple[list[Tile], BatchResult]]:
        """Return the next batch back (or none after ``timeout`` seconds), with its tiles.

        Raises :class:`~pge_world.errors.WorldError` naming the tile when the task failed.
        """
        import ray

        ready, _ = ray.wait(list(self.pending), num_returns=1, timeout=timeout)
        back = []
        for ref in ready:
            batch = self.pending.pop(ref)
            back.append((batch, fetch(ref, batch)))
        return back

    def cancel(self) -> None:
        """Cancel every task still running (the run failed)."""
        import ray

        for ref in self.pending:
            ray.cancel(ref, force=True)


def submit(
    job: TileJob,
    retries: int,
    description: bytes | None,
    batches: Sequence[Sequence[Tile]],
) -> Running:
    """Submit one task of :func:`~.tile.grow_tiles` per batch (``SPREAD`` over the nodes).

    Each task reserves ``job["threads"]`` CPUs and is run again up to ``retries`` times when
    its worker or node dies. ``description`` (the bytes of ``variants.json``) goes once
    through the object store to tasks that do not see the world directory.
    """
    import ray
    from ray import cloudpickle

    from . import tile as tile_module

    # Ship the task's code with it: workers need Ray and pge, not this package.
    cloudpickle.register_pickle_by_value(tile_module)
    task = ray.remote(grow_tiles).options(
        num_cpus=job["threads"],
        max_retries=retries,
        retry_exceptions=False,
        scheduling_strategy="SPREAD",
    )
    shipped: ObjectRef[bytes | None] | None = None
    if description is not None:
        shipped = ray.put(description)
    pending = {}
    for batch in batches:
        ref = task.remote(job, [(t["i"], t["j"]) for t in batch], shipped)
        pending[ref] = list(batch)
    return Running(pending)


def failure(cause: BaseException | None, error: BaseException, batch: Sequence[Tile]) -> WorldError:
    """Return the one-line error of a batch task that raised ``cause`` (Ray's ``error`` wraps it).

    A :class:`~.tile.TileFailed` keeps pge's own ``tile I,J: FILE:LINE: message``, or is
    put on the batch's first tile.
    """
    first = f"tile {batch[0]['i']},{batch[0]['j']}"
    # The task's module travels by value (workers need only Ray and pge), so its exception
    # class is a copy: compare by name.
    if type(cause).__name__ == TileFailed.__name__:
        message = str(cause)
        return WorldError(message if message.startswith("tile ") else f"{first}: {message}")
    reason = last_line(str(cause if cause is not None else error))
    return WorldError(f"{first} failed: {reason}")


def fetch(ref: ObjectRef[BatchResult], batch: Sequence[Tile]) -> BatchResult:
    """Return the result of a batch task, or a one-line error naming the tile (:func:`failure`)."""
    import ray
    from ray.exceptions import RayError, RayTaskError

    try:
        result: BatchResult = ray.get(ref)
    except RayTaskError as e:
        raise failure(getattr(e, "cause", None), e, batch) from None
    except RayError as e:
        first = f"tile {batch[0]['i']},{batch[0]['j']}"
        raise WorldError(f"{first} failed after {type(e).__name__}: {last_line(str(e))}") from None
    return result
