"""A batch on a worker (``grow_tiles``) with a fake ``pge``, and the task's code by value."""

from __future__ import annotations

import getpass
import hashlib
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
    grow_tiles,
    instances_by_tile,
    last_line,
    pge_args,
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


def test_instances_come_from_the_stats_lines() -> None:
    stats = '{"tile": [0, 1], "instances": 5}\n\n{"tile": [2, 0]}\n'
    assert instances_by_tile(stats) == {(0, 1): 5, (2, 0): 0}


def test_a_batch_without_the_world_directory_returns_the_tiles_bytes(fake_pge: FakePge) -> None:
    result = grow_tiles(job(fake_pge.path), [(1, 0), (0, 2)], None)
    assert result["node"] == socket.gethostname() and result["seconds"] >= 0
    assert [(t["i"], t["j"], t["instances"]) for t in result["tiles"]] == [(1, 0, 10), (0, 2, 2)]
    for t in result["tiles"]:
        assert t["glb"].startswith(f"tile {t['i']},{t['j']} seed 7".encode())
        assert t["sha256"] == hashlib.sha256(t["glb"]).hexdigest()
        assert t["bytes"] == len(t["glb"])
    [call] = fake_pge.calls()
    assert call[:6] == ["run", "/w/forest.lua", "--seed", "7", "--set", "spin=0"]
    assert call[6:10] == ["--tile", "1,0", "--tile", "0,2"]
    assert call[10] == "--out-dir" and call[12:] == ["-q", "--stats", "--threads", "2"]


def test_standalone_tiles_use_this_machines_variant_cache(fake_pge: FakePge) -> None:
    grow_tiles(job(fake_pge.path, variant_cache=""), [(0, 0)], None)
    grow_tiles(job(fake_pge.path, variant_cache="/shared/cache"), [(0, 0)], None)
    first, second = fake_pge.calls()
    cache = str(Path(tempfile.gettempdir()) / f"pge-variants-{getpass.getuser()}")
    assert first[-2:] == ["--variant-cache", cache]
    assert second[-2:] == ["--variant-cache", "/shared/cache"]


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
    assert grown["sha256"] == hashlib.sha256(data).hexdigest() and grown["instances"] == 31
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
    assert str(e.value).startswith(f"pge wrote no tile on {socket.gethostname()}: ")


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
        "print(result['tiles'][0]['instances'], type(task).__module__)\n"
    )
    p = subprocess.run(
        [sys.executable, "-c", worker], input=payload, capture_output=True, check=False
    )
    assert p.returncode == 0, p.stderr.decode()
    assert p.stdout.decode().split() == ["11", "builtins"]
