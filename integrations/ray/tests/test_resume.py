"""Resume decisions: another world refused, tiles kept or grown again, tile files adopted."""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest
from fakes import tile_glb

from pge_world import manifest as mf
from pge_world import resume
from pge_world.errors import WorldError
from pge_world.records import JsonValue, Manifest, Tile, VariantsEntry

pytestmark = pytest.mark.unit

SCRIPT = Path("/w/forest.lua")
IDENT = mf.identity("ab" * 32, 1, [("spin", "0")])
VARIANTS: VariantsEntry = {
    "file": "variants.bin",
    "sha256": "0" * 64,
    "bytes": 9,
    "description": "variants.json",
    "descriptionSha256": "1" * 64,
    "descriptionBytes": 2,
}


def tile(i: int, j: int) -> Tile:
    return {"i": i, "j": j, "min": [0.0, 0.0], "max": [20.0, 20.0]}


def world(
    directory: Path, shared: bool, complete: bool = True, variants: VariantsEntry = VARIANTS
) -> Manifest:
    """Write a world of two tiles into ``directory``: its manifest."""
    entries = []
    for i in range(2):
        data = tile_glb(i, 0, shared=shared)
        path = directory / mf.tile_file(i, 0)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
        entries.append(mf.tile_entry(tile(i, 0), hashlib.sha256(data).hexdigest(), len(data), 7))
    mf.write(directory, IDENT, SCRIPT, {}, entries, complete, variants if shared else None)
    manifest = mf.read(directory)
    assert manifest is not None
    return manifest


def test_another_worlds_manifest_is_refused(tmp_path: Path) -> None:
    old = world(tmp_path, shared=True)
    resume.refuse_other_world(None, IDENT, "DIR")
    resume.refuse_other_world(old, IDENT, "DIR")
    other = mf.identity(IDENT["scriptSha256"], 2, [("spin", "0")])
    with pytest.raises(WorldError) as e:
        resume.refuse_other_world(old, other, "DIR")
    assert str(e.value) == (
        "DIR holds another world (script /w/forest.lua, seed 1, set {'spin': '0'}): "
        "choose another --out or delete it"
    )


def test_only_a_complete_world_with_intact_variants_waits_to_connect(tmp_path: Path) -> None:
    complete = world(tmp_path / "a", shared=True)
    partial = world(tmp_path / "b", shared=True, complete=False)
    assert resume.likely_work(None, True, False)
    assert resume.likely_work(partial, True, True)
    assert resume.likely_work(complete, True, False)
    assert not resume.likely_work(complete, True, True)
    assert not resume.likely_work(complete, False, False)


def test_tiles_of_the_same_form_are_kept_the_other_form_grown_again(tmp_path: Path) -> None:
    shared = world(tmp_path / "shared", shared=True)
    alone = world(tmp_path / "alone", shared=False)
    assert sorted(resume.kept_tiles(tmp_path / "shared", shared, True)) == [(0, 0), (1, 0)]
    assert resume.kept_tiles(tmp_path / "shared", shared, False) == {}
    assert sorted(resume.kept_tiles(tmp_path / "alone", alone, False)) == [(0, 0), (1, 0)]
    assert resume.kept_tiles(tmp_path / "alone", alone, True) == {}
    assert resume.kept_tiles(tmp_path / "none", None, True) == {}


def test_variants_written_again_differently_regrow_every_tile(tmp_path: Path) -> None:
    old = world(tmp_path, shared=True)
    assert not resume.variants_changed(old, True, VARIANTS)
    assert resume.variants_changed(old, True, {**VARIANTS, "sha256": "2" * 64})
    assert not resume.variants_changed(old, False, None)
    assert not resume.variants_changed(None, True, VARIANTS)


@pytest.mark.parametrize(
    "value, text, same",
    [
        (True, "true", True),
        (True, " TRUE ", True),
        (False, "false", True),
        (False, "0", False),
        (3, "3", True),
        (3, "3.0", True),
        (0.5, ".5", True),
        (3, "4", False),
        (3, "three", False),
        ("oak", "oak", True),
        ("oak", "Oak", False),
        (None, "x", False),
    ],
)
def test_a_recorded_parameter_matches_its_set_text(value: JsonValue, text: str, same: bool) -> None:
    assert resume.matches(value, text) is same


def test_a_tile_file_of_this_run_is_adopted(tmp_path: Path) -> None:
    data = tile_glb(2, 1, seed=4, params={"spin": 0, "broken": False}, instances=12)
    path = tmp_path / "tiles" / "2_1.glb"
    path.parent.mkdir()
    path.write_bytes(data)
    adopted = resume.adopt(tmp_path, tile(2, 1), 4, [("spin", "0")], None, True)
    assert adopted is not None
    entry, params = adopted
    assert entry == {
        "i": 2,
        "j": 1,
        "min": [0.0, 0.0],
        "max": [20.0, 20.0],
        "file": "tiles/2_1.glb",
        "sha256": hashlib.sha256(data).hexdigest(),
        "bytes": len(data),
        "instances": 12,
    }
    assert params == {"spin": 0, "broken": False}
    assert resume.adopt(tmp_path, tile(0, 0), 4, [], None, True) is None  # no file


@pytest.mark.parametrize(
    "seed, overrides, params, at, message",
    [
        (5, [], None, (2, 1), "written with another seed, parameters or tile"),
        (4, [("spin", "1")], None, (2, 1), "written with another seed, parameters or tile"),
        (4, [], {"spin": 9}, (2, 1), "written with another seed, parameters or tile"),
        (4, [], None, (1, 2), "written with another seed, parameters or tile"),
    ],
)
def test_a_tile_file_of_another_run_is_refused(
    tmp_path: Path,
    seed: int,
    overrides: list[tuple[str, str]],
    params: dict[str, JsonValue] | None,
    at: tuple[int, int],
    message: str,
) -> None:
    path = tmp_path / "tiles" / f"{at[0]}_{at[1]}.glb"
    path.parent.mkdir()
    # The file at (at) says it is tile 2,1 of seed 4.
    path.write_bytes(tile_glb(2, 1, seed=4))
    with pytest.raises(WorldError) as e:
        resume.adopt(tmp_path, tile(*at), seed, overrides, params, True)
    assert str(e.value) == f"{path}: {message}; delete it to grow it again, or choose another --out"


def test_a_tile_file_of_the_other_form_or_not_a_tile_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "tiles" / "0_0.glb"
    path.parent.mkdir()
    path.write_bytes(tile_glb(0, 0, shared=False))
    with pytest.raises(WorldError) as e:
        resume.adopt(tmp_path, tile(0, 0), 1, [], None, True)
    assert str(e.value) == (
        f"{path}: the tile carries its variants; run pge-world with --standalone-tiles, "
        "or delete it to grow it again"
    )
    path.write_bytes(tile_glb(0, 0, shared=True))
    with pytest.raises(WorldError) as e:
        resume.adopt(tmp_path, tile(0, 0), 1, [], None, False)
    assert "the tile refers to shared variants; run pge-world without" in str(e.value)
    path.write_bytes(b"not a glb at all, longer than twenty bytes")
    with pytest.raises(WorldError) as e:
        resume.adopt(tmp_path, tile(0, 0), 1, [], None, True)
    assert str(e.value) == f"{path}: not a tile (not a .glb file); delete it to grow it again"


def test_adopting_keeps_the_kept_tiles_and_adds_the_files_found(tmp_path: Path) -> None:
    old = world(tmp_path, shared=True)
    kept = resume.kept_tiles(tmp_path, old, True)
    (tmp_path / "tiles" / "0_1.glb").write_bytes(tile_glb(0, 1, params={"spin": 0}))
    tiles = [tile(0, 0), tile(1, 0), tile(0, 1), tile(1, 1)]
    done, params = resume.adopt_all(tmp_path, tiles, kept, 1, [("spin", "0")], None, True)
    assert sorted(done) == [(0, 0), (0, 1), (1, 0)]
    assert done[(0, 0)] == kept[(0, 0)]
    assert params == {"spin": 0}
    assert sorted(kept) == [(0, 0), (1, 0)]  # the kept tiles are not changed in place
