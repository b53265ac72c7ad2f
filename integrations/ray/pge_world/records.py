"""The records pge-world reads and writes, as typed dictionaries (they travel as JSON).

A :class:`Tile` is what ``pge tiles`` lists; a :class:`Manifest` is ``DIR/world.json``
with a :class:`TileEntry` per tile written and, when the tiles refer to shared variants,
a :class:`VariantsEntry`.
"""

from __future__ import annotations

from typing import TypedDict, Union

#: A JSON value (a parameter's value as ``extras.pge.params`` records it).
JsonValue = Union[None, bool, int, float, str, list["JsonValue"], dict[str, "JsonValue"]]

#: The declared parameters of a script and their values.
Params = dict[str, JsonValue]

#: A tile's index (i, j): the key of the tiles done.
TileKey = tuple[int, int]


class Tile(TypedDict):
    """A tile as ``pge tiles`` lists it: its index and its bounds (x, z) in metres."""

    i: int
    j: int
    min: list[float]
    max: list[float]


class TileEntry(Tile):
    """The manifest's record of a tile written: its file, SHA-256, length, instances."""

    file: str
    sha256: str
    bytes: int
    instances: int


class VariantsEntry(TypedDict):
    """The manifest's record of the shared variants: each file's name, SHA-256, length."""

    file: str
    sha256: str
    bytes: int
    description: str
    descriptionSha256: str
    descriptionBytes: int


class Identity(TypedDict):
    """What makes two runs the same world: the script's hash, the seed, the --set values."""

    scriptSha256: str | None
    seed: int
    set: dict[str, str]


class _ManifestRequired(TypedDict):
    format: str
    script: str
    scriptSha256: str | None
    seed: int
    set: dict[str, str]
    params: Params
    complete: bool
    instances: int
    tiles: list[TileEntry]


class Manifest(_ManifestRequired, total=False):
    """``DIR/world.json``: the world's identity, parameters and tiles written so far."""

    variants: VariantsEntry


def key(tile: Tile) -> TileKey:
    """Return the index (i, j) of ``tile``."""
    return (tile["i"], tile["j"])
