"""How pge-world cuts the tiles into batches (one task and one pge process each).

Without a cluster: every tile in exactly one batch, batches even, one per CPU slot but no more than
MAX_TILES_PER_TASK tiles each, or --tiles-per-task tiles each.
"""

import pytest

from pge_world.plan import MAX_TILES_PER_TASK, batches_of

pytestmark = pytest.mark.unit


@pytest.mark.parametrize(
    "tiles, slots, per_task, count",
    [
        (16, 2, 0, 2),  # the tests' cluster: two batches of eight
        (3, 8, 0, 3),  # fewer tiles than CPUs: one tile a batch
        (1600, 400, 0, 400),  # the 100 km² plan: four tiles a task
        (1600, 8, 0, 1600 // MAX_TILES_PER_TASK),  # a small cluster: capped, queued
        (10, 8, 4, 3),  # --tiles-per-task 4
        (5, 0, 0, 1),  # no CPU reported: one batch
    ],
)
def test_batches_hold_every_tile_once_and_are_even(
    tiles: int, slots: int, per_task: int, count: int
) -> None:
    todo = [{"i": k // 7, "j": k % 7} for k in range(tiles)]
    batches = batches_of(todo, slots, per_task)
    assert len(batches) == count
    flat = [(t["i"], t["j"]) for b in batches for t in b]
    assert sorted(flat) == sorted((t["i"], t["j"]) for t in todo)
    sizes = [len(b) for b in batches]
    assert max(sizes) - min(sizes) <= 1
    assert max(sizes) <= (per_task or MAX_TILES_PER_TASK)


def test_tiles_are_dealt_in_turn() -> None:
    # Neighbouring tiles (similar work) land in different batches.
    assert batches_of(list(range(10)), 3, 0) == [[0, 3, 6, 9], [1, 4, 7], [2, 5, 8]]
    assert batches_of(list(range(5)), 0, 2) == [[0, 3], [1, 4], [2]]
    assert batches_of([], 4, 0) == []
