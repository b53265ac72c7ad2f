"""Resuming: what an earlier run (or a job array) left in the world directory, kept or not.

A tile is kept when the manifest lists it and its file still has the recorded hash, or
(``--adopt``) when a tile file the manifest does not list was written with this run's seed,
parameters and tile index. Tiles of the other form (standalone or referring to shared
variants) and tiles that refer to variants written again differently are grown again.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path

from . import glb
from . import manifest as mf
from .errors import WorldError
from .records import Identity, JsonValue, Manifest, Params, Tile, TileEntry, TileKey, key


def refuse_other_world(old: Manifest | None, ident: Identity, out: str) -> None:
    """Raise when the manifest ``old`` of ``out`` is of another world than ``ident``."""
    if old is not None and not mf.same_world(old, ident):
        raise WorldError(
            f"{out} holds another world (script {old.get('script')}, seed "
            f"{old.get('seed')}, set {old.get('set')}): choose another --out or delete it"
        )


def likely_work(old: Manifest | None, shared: bool, variants_ok: bool) -> bool:
    """Whether a run likely grows something, so connects to Ray at once.

    A complete world with intact variants is checked first, without Ray.
    """
    return old is None or not old.get("complete") or (shared and not variants_ok)


def kept_tiles(directory: Path, old: Manifest | None, shared: bool) -> dict[TileKey, TileEntry]:
    """Return the tiles of the manifest ``old`` kept: their files intact, of this run's form.

    Tiles of the other form (standalone or referring to shared variants) are grown again.
    """
    if old is None or (old.get("variants") is not None) != shared:
        return {}
    return mf.done_tiles(directory, old)


def variants_changed(old: Manifest | None, shared: bool, variants: object) -> bool:
    """Whether the shared variants were written again differently (another ``pge``).

    Every tile refers to them: every tile grows again.
    """
    recorded = old.get("variants") if old is not None else None
    return shared and recorded is not None and recorded != variants


def matches(value: JsonValue, text: str) -> bool:
    """Whether a parameter's recorded ``value`` is what ``--set NAME=text`` gives."""
    if isinstance(value, bool):
        return text.strip().lower() == json.dumps(value)
    if isinstance(value, (int, float)):
        try:
            return float(text) == value
        except ValueError:
            return False
    return value == text


def refers_to_variants(data: bytes) -> bool:
    """Whether a tile's .glb refers to the world's shared variants rather than carries them.

    It does when a buffer's URI is ``../variants.bin``.
    """
    return "../" + mf.VARIANTS_BIN in glb.buffer_uris(data)


def adopt(
    directory: Path,
    tile: Tile,
    seed: int,
    overrides: Sequence[tuple[str, str]],
    params: Params | None,
    shared: bool,
) -> tuple[TileEntry, Params] | None:
    """Return the manifest entry and parameters of ``tile``'s file in ``directory``, if any.

    The file must have been written by ``pge run --tile`` with this seed and these settings,
    referring to the shared variants when ``shared`` (``--variants DIR``) and carrying them
    otherwise. None when there is no file; an error when it belongs to another run or is of
    the other form.
    """
    path = directory / mf.tile_file(tile["i"], tile["j"])
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        return None
    except OSError as e:
        raise WorldError(f"{path}: {e}") from e
    try:
        extras = glb.root_extras(data)
        refers = refers_to_variants(data)
    except (WorldError, ValueError) as e:
        raise WorldError(f"{path}: not a tile ({e}); delete it to grow it again") from e
    if refers != shared:
        form = "refers to shared variants" if refers else "carries its variants"
        other = "without" if refers else "with"
        raise WorldError(
            f"{path}: the tile {form}; run pge-world {other} --standalone-tiles, or delete it "
            "to grow it again"
        )
    forest = extras.get("forest") or {}
    tile_params: Params = extras.get("params") or {}
    same = (
        forest.get("tileIndex") == [tile["i"], tile["j"]]
        and extras.get("seed") == seed
        and all(matches(tile_params.get(k), v) for k, v in overrides)
        and (params is None or tile_params == params)
    )
    if not same:
        raise WorldError(
            f"{path}: written with another seed, parameters or tile; delete it to grow it "
            "again, or choose another --out"
        )
    entry = mf.tile_entry(tile, mf.sha256_bytes(data), len(data), int(forest.get("instances", 0)))
    return entry, tile_params


def adopt_all(
    directory: Path,
    tiles: Sequence[Tile],
    kept: Mapping[TileKey, TileEntry],
    seed: int,
    overrides: Sequence[tuple[str, str]],
    params: Params | None,
    shared: bool,
) -> tuple[dict[TileKey, TileEntry], Params | None]:
    """Return the tiles kept with every tile file not kept adopted (:func:`adopt`), and the params.

    The parameters are those of the last tile adopted, else ``params``.
    """
    done = dict(kept)
    for t in tiles:
        if key(t) not in done:
            adopted = adopt(directory, t, seed, overrides, params, shared)
            if adopted is not None:
                done[key(t)], params = adopted
    return done, params
