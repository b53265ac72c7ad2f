"""A batch on a worker (``grow_tiles``) with a fake ``pge``, and the task's code by value."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
from conftest import FakePge

from pge_world.tile import (
    TileFailed,
    TileJob,
    default_variant_cache,
    die_with_parent,
    grow_tiles,
    last_line,
    pge_args,
    private_folder,
)

pytestmark = pytest.mark.unit

SCRIPT = Path("/w/forest.lua")


def job(program: str, **changes: object) -> TileJob:
    base: TileJob = {
        "program": program,
        "script": SCRIPT,
        "seed": 7,
        "overrides": [("spin", "0")],
        "threads": 2,
        "time_limit": None,
        "variant_cache": None,
        "shared": False,
        "out": None,
    }
    base.update(changes)  # type: ignore[typeddict-item]
    return base


def test_the_last_line_is_pges_error() -> None:
    assert last_line("warming up\nforest.lua:3: boom \n\n") == "forest.lua:3: boom"
    assert last_line(" \n") == ""


def test_every_pge_call_shares_script_seed_sets_and_time_limit() -> None:
    assert pge_args(SCRIPT, 3, [("a", "1"), ("b", "x=y")]) == [
        "/w/forest.lua",
        "--seed",
        "3",
        "--set",
        "a=1",
        "--set",
        "b=x=y",
    ]
    assert pge_args(SCRIPT, 3, [], 2.5)[-2:] == ["--time-limit", "2.5"]


def test_a_batch_without_the_world_directory_returns_the_tiles_bytes(fake_pge: FakePge) -> None:
    result = grow_tiles(job(fake_pge.path), [(1, 0), (0, 2)], None)
    assert result["node"] == socket.gethostname() and result["seconds"] >= 0
    assert [(t["i"], t["j"]) for t in result["tiles"]] == [(1, 0), (0, 2)]
    for t in result["tiles"]:
        assert t["glb"] == f"tile {t['i']},{t['j']} seed 7 ".encode()
    [call] = fake_pge.calls()
    assert call[:6] == ["run", "/w/forest.lua", "--seed", "7", "--set", "spin=0"]
    assert call[6:10] == ["--tile", "1,0", "--tile", "0,2"]
    assert call[10] == "--out-dir" and call[12:] == ["-q", "--threads", "2"]


def test_standalone_tiles_use_this_machines_variant_cache(
    fake_pge: FakePge, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    grow_tiles(job(fake_pge.path, variant_cache=""), [(0, 0)], None)
    grow_tiles(job(fake_pge.path, variant_cache="/shared/cache"), [(0, 0)], None)
    first, second = fake_pge.calls()
    cache = tmp_path / f"pge-variants-{os.getuid()}"
    assert default_variant_cache() == cache
    assert first[-2:] == ["--variant-cache", str(cache)]
    assert second[-2:] == ["--variant-cache", "/shared/cache"]
    # Created private to this user.
    assert cache.is_dir() and (cache.stat().st_mode & 0o777) == 0o700


def test_the_default_variant_cache_is_refused_unless_private(tmp_path: Path) -> None:
    mine = tmp_path / "mine"
    assert private_folder(mine) == mine and (mine.stat().st_mode & 0o777) == 0o700
    assert private_folder(mine) == mine  # already there, still private
    open_to_all = tmp_path / "open"
    open_to_all.mkdir()
    open_to_all.chmod(0o777)
    planted = tmp_path / "planted"
    planted.symlink_to(mine)
    a_file = tmp_path / "file"
    a_file.write_text("x")
    for path, why in [
        (open_to_all, "writable by others (mode 777)"),
        (planted, "not a folder"),
        (a_file, "not a folder"),
    ]:
        with pytest.raises(TileFailed) as e:
            private_folder(path)
        assert str(e.value).startswith(f"the variant cache {path} on ") and why in str(e.value)
    group = tmp_path / "group"
    group.mkdir()
    group.chmod(0o770)
    with pytest.raises(TileFailed, match="writable by others"):
        private_folder(group)
    # Owned by someone else (another uid than the folder's owner).
    with pytest.raises(TileFailed, match="owned by another user"):
        private_folder(mine, uid=os.getuid() + 1)


def test_a_worker_starts_pge_without_a_preexec_fn(
    fake_pge: FakePge, monkeypatch: pytest.MonkeyPatch
) -> None:
    # pge dies with the worker through `setpriv --pdeathsig KILL` where there is one, not
    # through Python code run between fork and exec in a multi-threaded worker.
    seen: list[tuple[list[str], dict[str, object]]] = []
    real = subprocess.run

    def spy(cmd: list[str], **kwargs: object) -> object:
        seen.append((cmd, kwargs))
        return real(cmd, **kwargs)  # type: ignore[call-overload]

    monkeypatch.setattr(subprocess, "run", spy)
    grow_tiles(job(fake_pge.path), [(0, 0)], None)
    [(cmd, kwargs)] = seen
    assert kwargs.get("preexec_fn") is None
    setpriv = shutil.which("setpriv")
    prefix = [setpriv, "--pdeathsig", "KILL", "--"] if setpriv else []
    assert die_with_parent() == prefix
    assert cmd[: len(prefix) + 2] == [*prefix, shutil.which(fake_pge.path), "run"]


def test_shared_tiles_get_the_description_in_a_scratch_world(fake_pge: FakePge) -> None:
    result = grow_tiles(job(fake_pge.path, shared=True), [(0, 0)], b"the description")
    assert result["tiles"][0]["glb"] == b"tile 0,0 seed 7 the description"
    [call] = fake_pge.calls()
    assert "--variants" in call and "--variant-cache" not in call


def test_a_batch_in_the_world_directory_leaves_the_tiles_there(
    fake_pge: FakePge, tmp_path: Path
) -> None:
    (tmp_path / "tiles").mkdir()
    (tmp_path / "variants.json").write_text("world's")
    result = grow_tiles(job(fake_pge.path, shared=True, out=tmp_path), [(3, 1)], None)
    [grown] = result["tiles"]
    assert "glb" not in grown
    data = (tmp_path / "tiles" / "3_1.glb").read_bytes()
    assert data == b"tile 3,1 seed 7 world's"
    assert grown == {"i": 3, "j": 1}
    [call] = fake_pge.calls()
    assert call[call.index("--variants") + 1] == str(tmp_path)
    assert call[call.index("--out-dir") + 1] == str(tmp_path / "tiles")


def test_a_world_directory_the_worker_does_not_see_fails_for_good(
    fake_pge: FakePge, tmp_path: Path
) -> None:
    with pytest.raises(TileFailed) as e:
        grow_tiles(job(fake_pge.path, out=tmp_path / "elsewhere"), [(0, 0)], None)
    assert str(e.value).startswith(f"the world directory {tmp_path / 'elsewhere'} is not on")
    assert fake_pge.calls() == []


def test_no_pge_on_the_worker_fails_for_good() -> None:
    with pytest.raises(TileFailed) as e:
        grow_tiles(job("no-such-pge-here"), [(0, 0)], None)
    assert str(e.value) == (
        f"no `no-such-pge-here` program on the PATH of the worker on {socket.gethostname()}: "
        "install pge there, or pass --pge with its path on the workers"
    )


def test_pges_error_is_the_tiles_message(fake_pge: FakePge) -> None:
    failing = job(fake_pge.path, overrides=[("fail", "tile 0,0: forest.lua:12: no sap")])
    with pytest.raises(TileFailed) as e:
        grow_tiles(failing, [(0, 0)], None)
    assert str(e.value) == "tile 0,0: forest.lua:12: no sap"


def test_a_pge_that_reports_no_tile_fails(fake_pge: FakePge) -> None:
    with pytest.raises(TileFailed) as e:
        grow_tiles(job(fake_pge.path, overrides=[("quiet", "1")]), [(0, 0)], None)
    assert str(e.value).startswith(f"pge wrote no tile 0,0 on {socket.gethostname()}: ")


def test_the_task_travels_by_value_to_a_worker_without_the_package(
    fake_pge: FakePge,
) -> None:
    # What Ray does with the task: pickle the function (its module by value, as
    # cluster.submit registers it) and its arguments, and run it where pge_world cannot be
    # imported.
    from ray import cloudpickle

    from pge_world import tile as tile_module

    cloudpickle.register_pickle_by_value(tile_module)
    try:
        payload = cloudpickle.dumps((grow_tiles, job(fake_pge.path), [(1, 1)]))
    finally:
        cloudpickle.unregister_pickle_by_value(tile_module)
    worker = (
        "import pickle, sys\n"
        "sys.modules['pge_world'] = None  # not installed on this worker\n"
        "task, job, tiles = pickle.loads(sys.stdin.buffer.read())\n"
        "result = task(job, tiles, None)\n"
        "print(result['tiles'][0]['glb'].decode().split()[1], type(task).__module__)\n"
    )
    p = subprocess.run(
        [sys.executable, "-c", worker], input=payload, capture_output=True, check=False
    )
    assert p.returncode == 0, p.stderr.decode()
    assert p.stdout.decode().split() == ["1,1", "builtins"]
