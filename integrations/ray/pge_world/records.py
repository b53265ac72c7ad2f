"""The records pge-world reads, as typed dictionaries (they travel as JSON).

A :class:`Tile` is what ``pge tiles`` lists; a :class:`VariantsEntry` is the manifest's
record of the shared variants, as ``pge world variants`` prints it.
"""

from __future__ import annotations

from typing import TypedDict

#: A tile's index (i, j): the key of the tiles done.
TileKey = tuple[int, int]


class Tile(TypedDict):
    """A tile as ``pge tiles`` lists it: its index and its bounds (x, z) in metres."""

    i: int
    j: int
    min: list[float]
    max: list[float]


class VariantsEntry(TypedDict):
    """The manifest's record of the shared variants: each file's name, SHA-256, length."""

    file: str
    sha256: str
    bytes: int
    description: str
    descriptionSha256: str
    descriptionBytes: int


def key(tile: Tile) -> TileKey:
    """Return the index (i, j) of ``tile``."""
    return (tile["i"], tile["j"])
