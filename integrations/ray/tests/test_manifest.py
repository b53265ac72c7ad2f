"""The world directory through ``pge world``: the calls, their output read, errors as one line.

A fake ``pge`` here; the real one is tested in Rust (tests/world.rs).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from conftest import FakePge

from pge_world import manifest as mf
from pge_world.errors import WorldError

pytestmark = pytest.mark.unit

SCRIPT = Path("/w/forest.lua")


def test_init_opens_the_directory_with_the_worlds_identity_and_form(
    tmp_path: Path, fake_pge: FakePge, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = tmp_path / "w"
    opened = mf.init(fake_pge.path, SCRIPT, 3, [("spin", "0"), ("a", "b=c")], out, True)
    assert opened == mf.Opened(
        created=True, fresh=True, complete=False, variants=False, tiles=frozenset()
    )
    state = (
        '{"created": false, "fresh": false, "complete": true, "variants": true,'
        ' "tiles": [[0, 1], [2, 0]]}'
    )
    monkeypatch.setenv("FAKE_WORLD_INIT", state)
    opened = mf.init(fake_pge.path, SCRIPT, 3, [], out, False)
    assert opened.tiles == {(0, 1), (2, 0)} and opened.complete and not opened.created
    first, second = fake_pge.calls()
    assert first == [
        "world",
        "init",
        "/w/forest.lua",
        "--out",
        str(out),
        "--seed",
        "3",
        "--set",
        "spin=0",
        "--set",
        "a=b=c",
    ]
    assert second[-1] == "--standalone-tiles"


def test_pges_refusal_is_its_last_line(tmp_path: Path, fake_pge: FakePge) -> None:
    refusal = "w holds another world (script /w/a.lua, seed 2, set {}): choose another --out"
    with pytest.raises(WorldError) as e:
        mf.init(fake_pge.path, SCRIPT, 1, [("fail", refusal)], tmp_path, True)
    assert str(e.value) == refusal
    with pytest.raises(WorldError) as e:
        mf.init(str(tmp_path / "nothing"), SCRIPT, 1, [], tmp_path, True)
    assert str(e.value).startswith(f"cannot run {tmp_path / 'nothing'}: ")


def test_a_failed_run_leaves_the_folder_as_it_was(tmp_path: Path) -> None:
    def opened(created: bool, fresh: bool) -> mf.Opened:
        return mf.Opened(created, fresh, complete=False, variants=False, tiles=frozenset())

    new = tmp_path / "new"
    (new / "tiles").mkdir(parents=True)
    mf.forget(new, opened(created=True, fresh=True))
    assert not new.exists()
    jobs = tmp_path / "jobs"  # tiles left by a job array, no manifest before the run
    (jobs / "tiles").mkdir(parents=True)
    (jobs / "tiles" / "0_0.glb").write_bytes(b"tile")
    (jobs / "world.json").write_text("{}")
    mf.forget(jobs, opened(created=False, fresh=True))
    assert sorted(p.name for p in jobs.rglob("*")) == ["0_0.glb", "tiles"]
    (jobs / "world.json").write_text("{}")  # an earlier run's manifest stays
    mf.forget(jobs, opened(created=False, fresh=False))
    assert (jobs / "world.json").exists()


def test_a_pge_that_prints_no_json_is_an_error(tmp_path: Path) -> None:
    old = tmp_path / "old-pge"
    old.write_text("#!/bin/sh\necho 'pge 0.0: no such command'\n")
    old.chmod(0o755)
    with pytest.raises(WorldError, match="printed no JSON"):
        mf.adopt(str(old), tmp_path)


def test_variants_tiles_adoption_and_the_end_are_recorded_by_pge(
    tmp_path: Path, fake_pge: FakePge, monkeypatch: pytest.MonkeyPatch
) -> None:
    changed, record = mf.record_variants(fake_pge.path, tmp_path)
    assert not changed and record["file"] == "variants.bin" and record["bytes"] == 1
    monkeypatch.setenv("FAKE_WORLD_CHANGED", "1")
    assert mf.record_variants(fake_pge.path, tmp_path)[0]
    mf.add(fake_pge.path, tmp_path, [(1, 0), (0, 12)])
    mf.add(fake_pge.path, tmp_path, [])  # nothing to record: pge is not run
    assert mf.adopt(fake_pge.path, tmp_path) == [(1, 0)]
    assert mf.finish(fake_pge.path, tmp_path) == 42
    calls = fake_pge.calls()
    assert calls[2] == ["world", "add", str(tmp_path), "1,0", "0,12"]
    assert [c[1] for c in calls] == ["variants", "variants", "add", "adopt", "finish"]


def test_a_failed_atomic_write_leaves_the_old_file_and_no_temporary(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    target = tmp_path / "0_0.glb"
    target.write_bytes(b"old")

    def no_rename(src: str, dst: Path) -> None:
        raise OSError(28, "No space left on device")

    with monkeypatch.context() as m:
        m.setattr(os, "replace", no_rename)
        with pytest.raises(OSError):
            mf.write_atomically(target, b"new")
    assert target.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["0_0.glb"]
    mf.write_atomically(target, b"new")
    assert target.read_bytes() == b"new"
    assert target.stat().st_mode & 0o777 == 0o644
