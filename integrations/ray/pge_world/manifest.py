"""The world directory: ``DIR/tiles/I_J.glb``, the shared variants and ``DIR/world.json``.

The manifest is always written whole (a temporary file renamed over the old one). While a
world grows it lists the tiles done so far with ``"complete": false``; the last write has
``"complete": true``. A run on the same directory skips every listed tile whose file still
has the recorded SHA-256 (:func:`done_tiles`).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import tempfile
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import cast

from . import glb
from .errors import WorldError
from .records import Identity, Manifest, Params, Tile, TileEntry, TileKey, VariantsEntry, key

FORMAT = "pge-world/1"
MANIFEST = "world.json"
VARIANTS_BIN = "variants.bin"
VARIANTS_JSON = "variants.json"


def sha256_bytes(data: bytes) -> str:
    """Return the SHA-256 of ``data`` as 64 hex digits."""
    return hashlib.sha256(data).hexdigest()


def sha256_file(path: Path) -> str | None:
    """Return the SHA-256 of the file at ``path``, or None when it cannot be read."""
    try:
        return sha256_bytes(path.read_bytes())
    except OSError:
        return None


def tile_file(i: int, j: int) -> str:
    """Return the file of tile (i, j), relative to the world directory."""
    return f"tiles/{i}_{j}.glb"


def tile_entry(tile: Tile, data_sha256: str, size: int, instances: int) -> TileEntry:
    """Return the manifest's record of ``tile`` written as a file of that hash and length."""
    return {
        "i": tile["i"],
        "j": tile["j"],
        "min": tile["min"],
        "max": tile["max"],
        "file": tile_file(tile["i"], tile["j"]),
        "sha256": data_sha256,
        "bytes": size,
        "instances": instances,
    }


def write_atomically(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file renamed over it."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def identity(
    script_sha256: str | None, seed: int, overrides: Iterable[tuple[str, str]]
) -> Identity:
    """Return the identity of a world (:class:`~pge_world.records.Identity`)."""
    return {"scriptSha256": script_sha256, "seed": seed, "set": dict(overrides)}


def read(directory: Path) -> Manifest | None:
    """Return the manifest in ``directory``, or None when there is none."""
    path = directory / MANIFEST
    if not path.exists():
        return None
    try:
        with path.open(encoding="utf-8") as f:
            manifest = json.load(f)
    except (OSError, ValueError) as e:
        raise WorldError(f"{path}: not a world manifest ({e}); choose another --out") from e
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        raise WorldError(f"{path}: not a {FORMAT} manifest; choose another --out")
    return cast(Manifest, manifest)


def same_world(manifest: Manifest, ident: Identity) -> bool:
    """Whether ``manifest`` was written for the world ``ident`` (see :func:`identity`)."""
    return (
        manifest.get("scriptSha256") == ident["scriptSha256"]
        and manifest.get("seed") == ident["seed"]
        and manifest.get("set") == ident["set"]
    )


def done_tiles(directory: Path, manifest: Manifest) -> dict[TileKey, TileEntry]:
    """Return the tiles of ``manifest`` whose file in ``directory`` still has the recorded hash."""
    done = {}
    for t in manifest.get("tiles", []):
        if sha256_file(directory / t["file"]) == t["sha256"]:
            done[key(t)] = t
    return done


def variants_entry(directory: Path) -> VariantsEntry | None:
    """Return the record of the shared variants in ``directory``; None when either file is missing.

    They are the files ``pge run --variants-out`` writes: the binary and its description.
    """
    try:
        binary = (directory / VARIANTS_BIN).read_bytes()
        description = (directory / VARIANTS_JSON).read_bytes()
    except OSError:
        return None
    return {
        "file": VARIANTS_BIN,
        "sha256": sha256_bytes(binary),
        "bytes": len(binary),
        "description": VARIANTS_JSON,
        "descriptionSha256": sha256_bytes(description),
        "descriptionBytes": len(description),
    }


def variants_intact(directory: Path, manifest: Manifest) -> bool:
    """Whether the shared variants ``manifest`` records are in ``directory`` unchanged."""
    recorded = manifest.get("variants")
    return recorded is not None and variants_entry(directory) == recorded


def tile_params(data: bytes) -> Params:
    """Return the declared parameters' values recorded in a tile (its ``extras.pge.params``)."""
    params: Params = glb.root_extras(data).get("params", {})
    return params


def write(
    directory: Path,
    ident: Identity,
    script: Path,
    params: Params,
    tiles: Iterable[TileEntry],
    complete: bool,
    variants: VariantsEntry | None = None,
) -> None:
    """Write the manifest atomically.

    It lists ``tiles`` in (i, j) order with their instance total, and the shared variants'
    record (:func:`variants_entry`) when the tiles refer to them.
    """
    ordered = sorted(tiles, key=key)
    manifest: Manifest = {
        "format": FORMAT,
        "script": str(script),
        "scriptSha256": ident["scriptSha256"],
        "seed": ident["seed"],
        "set": ident["set"],
        "params": params,
        "complete": complete,
        "instances": sum(t["instances"] for t in ordered),
        "tiles": ordered,
    }
    if variants is not None:
        manifest["variants"] = variants
    text = json.dumps(_in_order(manifest), indent=1) + "\n"
    write_atomically(directory / MANIFEST, text.encode("utf-8"))


#: The manifest's keys in the order it is written (the variants before ``complete``).
_ORDER: Sequence[str] = (
    "format",
    "script",
    "scriptSha256",
    "seed",
    "set",
    "params",
    "variants",
    "complete",
    "instances",
    "tiles",
)


def _in_order(manifest: Manifest) -> dict[str, object]:
    fields: Mapping[str, object] = manifest
    return {k: fields[k] for k in _ORDER if k in fields}


def clean_scratch(folder: Path) -> None:
    """Remove what a ``pge`` killed while writing a tile left in ``folder``.

    That is its temporary ``.tmp*`` files; the tile itself is renamed into place whole or
    not at all.
    """
    for path in folder.iterdir():
        if path.name.startswith(".tmp"):
            with contextlib.suppress(OSError):
                path.unlink()
