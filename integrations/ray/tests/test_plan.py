"""The tile list ``pge tiles`` prints, read into tiles, and the CPU slots of a cluster."""

from __future__ import annotations

import json

import pytest

from pge_world.errors import WorldError
from pge_world.plan import parse_tiles, slots

pytestmark = pytest.mark.unit

LISTED = [
    {"i": 0, "j": 0, "min": [-40.0, -40.0], "max": [-20.0, -20.0]},
    {"i": 1, "j": 0, "min": [-20.0, -40.0], "max": [0.0, -20.0], "future": "ignored"},
]


def test_a_tile_list_is_read_into_tiles() -> None:
    tiles = parse_tiles(json.dumps(LISTED), "/w/forest.lua")
    assert tiles == [
        {"i": 0, "j": 0, "min": [-40.0, -40.0], "max": [-20.0, -20.0]},
        {"i": 1, "j": 0, "min": [-20.0, -40.0], "max": [0.0, -20.0]},
    ]


@pytest.mark.parametrize(
    "text, message",
    [
        ("", "pge tiles printed no tile list: "),
        ("{", "pge tiles printed no tile list: "),
        ('{"i": 0}', "pge tiles printed no tile list: not a JSON list"),
        ('[{"i": 0, "j": 0, "min": [0, 0]}]', "entry 0 is not a tile"),
        ('[{"i": "0", "j": 0, "min": [0, 0], "max": [1, 1]}]', "entry 0 is not a tile"),
        ('[{"i": true, "j": 0, "min": [0, 0], "max": [1, 1]}]', "entry 0 is not a tile"),
        ('[{"i": 0, "j": 0, "min": [0, 0, 0], "max": [1, 1]}]', "entry 0 is not a tile"),
        ('[{"i": 0, "j": 0, "min": [0, "a"], "max": [1, 1]}]', "entry 0 is not a tile"),
        ("[[0, 0]]", "entry 0 is not a tile"),
        ("[]", "/w/forest.lua: the forest has no tiles"),
    ],
)
def test_anything_but_a_list_of_tiles_is_an_error(text: str, message: str) -> None:
    with pytest.raises(WorldError) as e:
        parse_tiles(text, "/w/forest.lua")
    assert message in str(e.value)


@pytest.mark.parametrize(
    "cpus, per_tile, expected",
    [([1, 1], 1, 2), ([8, 8, 4], 1, 20), ([8, 3], 2, 5), ([1], 2, 0), ([], 1, 0)],
)
def test_slots_are_each_nodes_cpus_over_a_tasks(
    cpus: list[int], per_tile: int, expected: int
) -> None:
    assert slots(cpus, per_tile) == expected
