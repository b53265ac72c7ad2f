"""The world directory's manifest: written whole and in order, read back, verified."""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import pytest

from pge_world import manifest as mf
from pge_world.errors import WorldError
from pge_world.records import Tile, TileEntry, VariantsEntry

pytestmark = pytest.mark.unit

SCRIPT = Path("/w/forest.lua")
IDENT = mf.identity("ab" * 32, 3, [("spin", "0"), ("broken", "false")])


def tile(i: int, j: int) -> Tile:
    return {"i": i, "j": j, "min": [i * 20.0, j * 20.0], "max": [i * 20.0 + 20, j * 20.0 + 20]}


def written(directory: Path, i: int, j: int, data: bytes, instances: int = 5) -> TileEntry:
    """Write a tile file into ``directory``: its manifest entry."""
    path = directory / mf.tile_file(i, j)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(data)
    return mf.tile_entry(tile(i, j), hashlib.sha256(data).hexdigest(), len(data), instances)


def test_the_manifest_is_written_in_order_and_read_back(tmp_path: Path) -> None:
    entries = [written(tmp_path, 1, 0, b"b", 4), written(tmp_path, 0, 1, b"a", 6)]
    variants: VariantsEntry = {
        "file": "variants.bin",
        "sha256": "0" * 64,
        "bytes": 9,
        "description": "variants.json",
        "descriptionSha256": "1" * 64,
        "descriptionBytes": 2,
    }
    mf.write(tmp_path, IDENT, SCRIPT, {"spin": 0}, entries, False, variants)
    text = (tmp_path / "world.json").read_text()
    manifest = json.loads(text)
    # The key order is the format's (pge merge reads it; people diff it).
    assert list(manifest) == [
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
    ]
    assert manifest["format"] == "pge-world/1" and manifest["script"] == "/w/forest.lua"
    assert manifest["set"] == {"spin": "0", "broken": "false"} and manifest["seed"] == 3
    assert manifest["instances"] == 10 and manifest["complete"] is False
    # Tiles in (i, j) order, whatever order they came in.
    assert [(t["i"], t["j"]) for t in manifest["tiles"]] == [(0, 1), (1, 0)]
    assert text.endswith("}\n") and text.startswith('{\n "format"')
    assert mf.read(tmp_path) == manifest
    # Written through a temporary file renamed over it: nothing else is left.
    assert sorted(p.name for p in tmp_path.iterdir()) == ["tiles", "world.json"]


def test_without_shared_variants_the_manifest_has_no_variants(tmp_path: Path) -> None:
    mf.write(tmp_path, IDENT, SCRIPT, {}, [written(tmp_path, 0, 0, b"x")], True)
    manifest = mf.read(tmp_path)
    assert manifest is not None and "variants" not in manifest
    assert manifest["complete"] is True and manifest["instances"] == 5


def test_a_directory_without_a_manifest_reads_as_none(tmp_path: Path) -> None:
    assert mf.read(tmp_path) is None


@pytest.mark.parametrize(
    "text, message",
    [
        ("{", "not a world manifest"),
        ("[]", "not a pge-world/1 manifest"),
        ('{"format": "pge-world/0"}', "not a pge-world/1 manifest"),
    ],
)
def test_a_manifest_of_another_kind_is_refused(tmp_path: Path, text: str, message: str) -> None:
    (tmp_path / "world.json").write_text(text)
    with pytest.raises(WorldError) as e:
        mf.read(tmp_path)
    assert message in str(e.value) and "choose another --out" in str(e.value)


def test_the_same_world_is_the_same_script_seed_and_set(tmp_path: Path) -> None:
    mf.write(tmp_path, IDENT, SCRIPT, {}, [], True)
    manifest = mf.read(tmp_path)
    assert manifest is not None
    assert mf.same_world(manifest, IDENT)
    assert not mf.same_world(manifest, mf.identity("cd" * 32, 3, IDENT["set"].items()))
    assert not mf.same_world(manifest, mf.identity(IDENT["scriptSha256"], 4, IDENT["set"].items()))
    assert not mf.same_world(manifest, mf.identity(IDENT["scriptSha256"], 3, [("spin", "1")]))


def test_done_tiles_are_those_whose_file_has_the_recorded_hash(tmp_path: Path) -> None:
    entries = [written(tmp_path, i, 0, f"tile {i}".encode()) for i in range(4)]
    mf.write(tmp_path, IDENT, SCRIPT, {}, entries, False)
    (tmp_path / mf.tile_file(1, 0)).write_bytes(b"damaged")
    (tmp_path / mf.tile_file(2, 0)).unlink()
    manifest = mf.read(tmp_path)
    assert manifest is not None
    done = mf.done_tiles(tmp_path, manifest)
    assert sorted(done) == [(0, 0), (3, 0)]
    assert done[(3, 0)] == entries[3]


def test_the_variants_record_holds_both_files_hashes(tmp_path: Path) -> None:
    assert mf.variants_entry(tmp_path) is None
    (tmp_path / "variants.bin").write_bytes(b"meshes")
    assert mf.variants_entry(tmp_path) is None  # no description yet
    (tmp_path / "variants.json").write_bytes(b"{}")
    entry = mf.variants_entry(tmp_path)
    assert entry == {
        "file": "variants.bin",
        "sha256": hashlib.sha256(b"meshes").hexdigest(),
        "bytes": 6,
        "description": "variants.json",
        "descriptionSha256": hashlib.sha256(b"{}").hexdigest(),
        "descriptionBytes": 2,
    }
    mf.write(tmp_path, IDENT, SCRIPT, {}, [], True, entry)
    manifest = mf.read(tmp_path)
    assert manifest is not None and mf.variants_intact(tmp_path, manifest)
    (tmp_path / "variants.bin").write_bytes(b"meshe5")
    assert not mf.variants_intact(tmp_path, manifest)
    mf.write(tmp_path, IDENT, SCRIPT, {}, [], True)
    without = mf.read(tmp_path)
    assert without is not None and not mf.variants_intact(tmp_path, without)


def test_a_failed_atomic_write_leaves_the_old_file_and_no_temporary(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    target = tmp_path / "world.json"
    target.write_bytes(b"old")

    def no_rename(src: str, dst: Path) -> None:
        raise OSError(28, "No space left on device")

    with monkeypatch.context() as m:
        m.setattr(os, "replace", no_rename)
        with pytest.raises(OSError):
            mf.write_atomically(target, b"new")
    assert target.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["world.json"]
    mf.write_atomically(target, b"new")
    assert target.read_bytes() == b"new"
    assert target.stat().st_mode & 0o777 == 0o644


def test_clean_scratch_removes_only_pges_temporaries(tmp_path: Path) -> None:
    for name in (".tmp123", ".tmpabc.glb", "0_0.glb", "tmp.glb"):
        (tmp_path / name).write_bytes(b"")
    mf.clean_scratch(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["0_0.glb", "tmp.glb"]
