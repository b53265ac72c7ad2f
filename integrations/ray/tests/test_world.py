"""pge-world on a real local Ray cluster (conftest.py).

Every tile's bytes equal a local
`pge run --tile`, the manifest is right, a killed worker changes nothing, a second run does
no work, and bad input is one line and exit 1.
"""

import hashlib
import json
import os
import signal
import subprocess
import sys
import time

import pytest
from conftest import FOREST


def root_extras(data):
    """Return a .glb's root ``extras.pge`` (its JSON chunk, after the 12-byte header)."""
    length = int.from_bytes(data[12:16], "little")
    return json.loads(data[20 : 20 + length])["extras"]["pge"]


# The console script the package installs, beside this Python.
CLI = [os.path.join(os.path.dirname(sys.executable), "pge-world")]


def pge_world(cluster, *args, **kw):
    """Run the console script against the cluster; returns the finished process."""
    cmd = [*CLI, FOREST, "--address", cluster.address]
    return subprocess.run(
        cmd + list(args), env=cluster.env, capture_output=True, text=True, timeout=600, **kw
    )


def local_tiles(pge_bin, folder, *sets):
    """Return every tile of the test forest run by `pge run --tile` here: (i, j) -> bytes."""
    extra = [a for s in sets for a in ("--set", s)]
    listed = subprocess.run(
        [pge_bin, "tiles", FOREST, *extra], capture_output=True, text=True, check=True
    )
    out = {}
    for t in json.loads(listed.stdout):
        path = os.path.join(folder, f"{t['i']}_{t['j']}.glb")
        subprocess.run(
            [pge_bin, "run", FOREST, "--tile", f"{t['i']},{t['j']}", "-o", path, "-q", *extra],
            check=True,
            capture_output=True,
        )
        with open(path, "rb") as f:
            out[(t["i"], t["j"])] = f.read()
    return out


def local_shared_tiles(pge_bin, folder, *sets):
    """Return the variants and every tile of the test forest as written on this machine.

    That is, as `pge run --variants-out` and `pge run --tile --variants` write them into
    ``folder`` (laid out as a world directory): ({file name: bytes} of the variants,
    {(i, j): tile bytes}).
    """
    extra = [a for s in sets for a in ("--set", s)]
    subprocess.run(
        [pge_bin, "run", FOREST, "--variants-out", folder, "-q", "--threads", "1", *extra],
        check=True,
        capture_output=True,
    )
    listed = subprocess.run(
        [pge_bin, "tiles", FOREST, *extra], capture_output=True, text=True, check=True
    )
    os.makedirs(os.path.join(folder, "tiles"), exist_ok=True)
    out = {}
    for t in json.loads(listed.stdout):
        path = os.path.join(folder, "tiles", f"{t['i']}_{t['j']}.glb")
        subprocess.run(
            [
                pge_bin,
                "run",
                FOREST,
                "--tile",
                f"{t['i']},{t['j']}",
                "--variants",
                folder,
                "-o",
                path,
                "-q",
                "--threads",
                "1",
                *extra,
            ],
            check=True,
            capture_output=True,
        )
        with open(path, "rb") as f:
            out[(t["i"], t["j"])] = f.read()
    variants = {}
    for name in ("variants.bin", "variants.json"):
        with open(os.path.join(folder, name), "rb") as f:
            variants[name] = f.read()
    return variants, out


@pytest.fixture(scope="module")
def reference(pge_bin, tmp_path_factory):
    """Return the local tiles of the forest as the tests run it (spin makes tiles slower)."""
    return local_tiles(pge_bin, str(tmp_path_factory.mktemp("local")), "spin=0")


def read_world(folder):
    with open(os.path.join(folder, "world.json"), encoding="utf-8") as f:
        return json.load(f)


def tile_bytes(folder, world):
    out = {}
    for t in world["tiles"]:
        with open(os.path.join(folder, t["file"]), "rb") as f:
            out[(t["i"], t["j"])] = f.read()
    return out


def test_a_world_is_the_local_tiles_and_a_second_run_does_no_work(cluster, reference, tmp_path):
    out = str(tmp_path / "world")
    variants = tmp_path / "variants"
    p = pge_world(
        cluster,
        "--out",
        out,
        "--set",
        "spin=0",
        "--variant-cache",
        str(variants),
        "--standalone-tiles",
    )
    assert p.returncode == 0, p.stderr
    assert "tiles 16/16" in p.stderr, p.stderr
    # The tiles shared the variants of the script species (shrub.lua, two variants) through
    # the cache: two entries, and still every tile's bytes equal a local run without it.
    entries = [n for n in os.listdir(variants) if n.endswith(".pgevariant")]
    assert len(entries) == 2, os.listdir(variants)
    world = read_world(out)
    assert world["complete"] is True
    assert world["seed"] == 1 and world["set"] == {"spin": "0"}
    with open(FOREST, "rb") as f:
        assert world["scriptSha256"] == hashlib.sha256(f.read()).hexdigest()
    assert world["params"] == {"spin": 0, "broken": False}
    got = tile_bytes(out, world)
    assert got == reference
    listed = json.loads(
        subprocess.run(
            ["pge", "tiles", FOREST], env=cluster.env, capture_output=True, text=True, check=True
        ).stdout
    )
    bounds = {(t["i"], t["j"]): (t["min"], t["max"]) for t in listed}
    total = 0
    for t in world["tiles"]:
        data = got[(t["i"], t["j"])]
        assert t["sha256"] == hashlib.sha256(data).hexdigest()
        assert t["bytes"] == len(data)
        assert (t["min"], t["max"]) == bounds[(t["i"], t["j"])]
        forest = root_extras(data)["forest"]
        assert t["instances"] == forest["instances"]
        total += t["instances"]
    assert world["instances"] == total > 0
    assert sorted(os.listdir(os.path.join(out, "tiles"))) == sorted(
        f"{i}_{j}.glb" for (i, j) in reference
    )

    # A second run on the same directory finds every tile and grows none.
    stamps = {
        n: os.stat(os.path.join(out, "tiles", n)).st_mtime_ns
        for n in os.listdir(os.path.join(out, "tiles"))
    }
    again = pge_world(cluster, "--out", out, "--set", "spin=0", "--standalone-tiles")
    assert again.returncode == 0, again.stderr
    assert "16 of 16 tiles already" in again.stderr and "nothing to do" in again.stderr
    assert {n: os.stat(os.path.join(out, "tiles", n)).st_mtime_ns for n in stamps} == stamps

    # A damaged tile is grown again, alone.
    damaged = os.path.join(out, world["tiles"][5]["file"])
    with open(damaged, "r+b") as f:
        f.write(b"XXXX")
    resumed = pge_world(cluster, "--out", out, "--set", "spin=0", "--standalone-tiles")
    assert resumed.returncode == 0, resumed.stderr
    assert "15 of 16 tiles already" in resumed.stderr, resumed.stderr
    assert tile_bytes(out, read_world(out)) == reference
    assert read_world(out) == world


@pytest.mark.parametrize("fs", ["--shared-fs", "--no-shared-fs"])
def test_tiles_that_share_their_variants_are_the_local_ones(cluster, pge_bin, tmp_path, fs):
    # The default: the variants written once (on the driver, every core), tiles that refer
    # to them; each file equal to the local runs on one thread. The tasks write the tiles
    # into the world directory themselves (a shared folder: this machine, the default here)
    # or send their bytes back through the object store (--no-shared-fs).
    variants, reference = local_shared_tiles(pge_bin, str(tmp_path / "local"), "spin=0")
    out = str(tmp_path / "world")
    p = pge_world(cluster, "--out", out, "--set", "spin=0", fs, "--timings")
    assert p.returncode == 0, p.stderr
    assert "tiles 16/16" in p.stderr and "variants:" in p.stderr, p.stderr
    # One task per CPU of the cluster (two), each one pge process for its eight tiles.
    assert p.stderr.count("batch of 8 tiles back from") == 2, p.stderr
    for name, data in variants.items():
        with open(os.path.join(out, name), "rb") as f:
            assert f.read() == data, name
    world = read_world(out)
    assert world["complete"] is True
    assert world["variants"] == {
        "file": "variants.bin",
        "sha256": hashlib.sha256(variants["variants.bin"]).hexdigest(),
        "bytes": len(variants["variants.bin"]),
        "description": "variants.json",
        "descriptionSha256": hashlib.sha256(variants["variants.json"]).hexdigest(),
        "descriptionBytes": len(variants["variants.json"]),
    }
    got = tile_bytes(out, world)
    assert got == reference
    for t in world["tiles"]:
        assert t["sha256"] == hashlib.sha256(got[(t["i"], t["j"])]).hexdigest()
        assert t["instances"] == root_extras(got[(t["i"], t["j"])])["forest"]["instances"]
    # Every tile is small: the variants are not in it.
    assert max(len(b) for b in got.values()) * 4 < len(variants["variants.bin"])

    # A second run does no work; damaged variants are written again, the tiles kept.
    stamps = {
        n: os.stat(os.path.join(out, "tiles", n)).st_mtime_ns
        for n in os.listdir(os.path.join(out, "tiles"))
    }
    again = pge_world(cluster, "--out", out, "--set", "spin=0")
    assert again.returncode == 0, again.stderr
    assert "16 of 16 tiles already" in again.stderr and "nothing to do" in again.stderr
    with open(os.path.join(out, "variants.bin"), "r+b") as f:
        f.write(b"XXXX")
    repaired = pge_world(cluster, "--out", out, "--set", "spin=0")
    assert repaired.returncode == 0, repaired.stderr
    assert "variants:" in repaired.stderr, repaired.stderr
    assert {n: os.stat(os.path.join(out, "tiles", n)).st_mtime_ns for n in stamps} == stamps
    assert read_world(out) == world
    with open(os.path.join(out, "variants.bin"), "rb") as f:
        assert f.read() == variants["variants.bin"]

    # The same directory grown again as standalone tiles: every tile is regrown.
    alone = pge_world(cluster, "--out", out, "--set", "spin=0", "--standalone-tiles")
    assert alone.returncode == 0, alone.stderr
    assert "already" not in alone.stderr, alone.stderr
    assert "variants" not in read_world(out)


def extra_node_workers(cluster):
    """Return the pids of the tile tasks running on the extra node.

    They are the workers whose parent is the raylet with the extra node's node-manager port.
    """

    def cmdline(pid):
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                return f.read().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            return ""

    def parent(pid):
        try:
            with open(f"/proc/{pid}/stat", encoding="utf-8") as f:
                return int(f.read().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            return None

    pids = [int(p) for p in os.listdir("/proc") if p.isdigit()]
    raylets = [
        p
        for p in pids
        if "raylet" in cmdline(p) and f"--node_manager_port={cluster.worker_port}" in cmdline(p)
    ]
    return [p for p in pids if parent(p) in raylets and "grow_tile" in cmdline(p)]


def test_killing_a_worker_in_the_middle_changes_nothing(cluster, pge_bin, tmp_path):
    # About a second of Lua per pge run: a tile is still running when its worker is killed.
    spin = "spin=12000000"
    _, reference = local_shared_tiles(pge_bin, str(tmp_path / "local"), spin)
    out = str(tmp_path / "world")
    cmd = [*CLI, FOREST, "--address", cluster.address, "--out", out, "--set", spin]
    run = subprocess.Popen(
        cmd, env=cluster.env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    killed: list[int] = []
    try:
        deadline = time.monotonic() + 300
        while not killed and run.poll() is None and time.monotonic() < deadline:
            for pid in extra_node_workers(cluster):
                os.kill(pid, signal.SIGKILL)
                killed.append(pid)
            time.sleep(0.2)
        _, err = run.communicate(timeout=600)
    finally:
        if run.poll() is None:
            run.kill()
    assert killed, "no tile ran on the extra node"
    assert run.returncode == 0, err
    world = read_world(out)
    assert world["complete"] is True
    assert tile_bytes(out, world) == reference


@pytest.mark.parametrize("mode", ["--standalone-tiles", "shared"])
def test_a_tile_that_fails_stops_the_run_with_its_message(cluster, tmp_path, mode):
    out = str(tmp_path / "world")
    extra = [mode] if mode.startswith("--") else []
    p = pge_world(cluster, "--out", out, "--set", "broken=true", *extra)
    assert p.returncode == 1
    lines = p.stderr.strip().splitlines()
    # Shared variants are written first, on the driver: the broken species fails there.
    where = "pge-world: tile " if extra else "pge-world: variants: "
    assert lines[-1].startswith(where), p.stderr
    assert "forest.lua:" in lines[-1] and "no sap in this species" in lines[-1], p.stderr
    assert "Traceback" not in p.stderr
    if os.path.exists(os.path.join(out, "world.json")):
        assert read_world(out)["complete"] is False


def test_no_cluster_is_one_line(cluster, tmp_path):
    from conftest import free_port

    out = tmp_path / "world"
    p = subprocess.run(
        [*CLI, FOREST, "--out", str(out), "--address", f"127.0.0.1:{free_port()}"],
        env=cluster.env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 1
    assert p.stderr.count("\n") == 1 and "no Ray cluster at 127.0.0.1:" in p.stderr, p.stderr
    assert "ray start --head" in p.stderr
    assert not out.exists()


def test_another_worlds_directory_is_refused(cluster, reference, tmp_path):
    out = tmp_path / "world"
    p = pge_world(cluster, "--out", str(out), "--set", "spin=0")
    assert p.returncode == 0, p.stderr
    before = (out / "world.json").read_bytes()
    other = pge_world(cluster, "--out", str(out), "--seed", "2")
    assert other.returncode == 1
    assert other.stderr.count("\n") == 1 and "holds another world" in other.stderr
    assert (out / "world.json").read_bytes() == before


def test_a_script_without_tile_is_one_line(cluster, tmp_path):
    script = tmp_path / "untiled.lua"
    script.write_text(
        "local f = pge.Forest{ size = {40, 40} }\n"
        f'f:scatter{{ species = "{os.path.dirname(FOREST)}/shrub.lua", minDistance = 5 }}\n'
        "return f\n"
    )
    out = tmp_path / "world"
    p = subprocess.run(
        [*CLI, str(script), "--out", str(out), "--address", cluster.address],
        env=cluster.env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 1
    assert p.stderr.count("\n") == 1 and "tile" in p.stderr, p.stderr
    assert not out.exists()


def test_pge_missing_on_the_workers_is_one_line(cluster, pge_bin, tmp_path):
    # `pge-only-here` is on the driver's PATH, not on the cluster's.
    local = tmp_path / "bin"
    local.mkdir()
    os.symlink(pge_bin, local / "pge-only-here")
    env = dict(cluster.env)
    env["PATH"] = str(local) + os.pathsep + env["PATH"]
    out = tmp_path / "world"
    p = subprocess.run(
        [*CLI, FOREST, "--out", str(out), "--address", cluster.address, "--pge", "pge-only-here"],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 1
    assert "no `pge-only-here` program on the PATH of the worker" in p.stderr, p.stderr
    assert p.stderr.strip().count("\n") == 0, p.stderr
    assert not (out / "world.json").exists()


def test_tiles_written_by_a_job_array_are_adopted(cluster, pge_bin, reference, tmp_path):
    # As a Kubernetes Indexed Job or a Slurm array leaves them: tiles, no manifest.
    out = tmp_path / "world"
    (out / "tiles").mkdir(parents=True)
    for (i, j), data in reference.items():
        if (i, j) != (3, 3):
            (out / "tiles" / f"{i}_{j}.glb").write_bytes(data)
    p = pge_world(cluster, "--out", str(out), "--set", "spin=0", "--adopt", "--standalone-tiles")
    assert p.returncode == 0, p.stderr
    assert "15 of 16 tiles already" in p.stderr, p.stderr
    world = read_world(str(out))
    assert world["complete"] is True and len(world["tiles"]) == 16
    assert tile_bytes(str(out), world) == reference

    # A tile of another seed is refused, not adopted.
    other = tmp_path / "other"
    (other / "tiles").mkdir(parents=True)
    (other / "tiles" / "0_0.glb").write_bytes(reference[(0, 0)])
    p = pge_world(cluster, "--out", str(other), "--seed", "5", "--adopt", "--standalone-tiles")
    assert p.returncode == 1
    assert "0_0.glb: written with another seed" in p.stderr, p.stderr
    assert not (other / "world.json").exists()


def test_shared_tiles_written_by_a_job_array_are_adopted(cluster, pge_bin, reference, tmp_path):
    # As deploy/'s Jobs leave them: the variants written first, then tiles that refer to
    # them, no manifest.
    out = tmp_path / "world"
    variants, shared = local_shared_tiles(pge_bin, str(out), "spin=0")
    (out / "tiles" / "3_3.glb").unlink()
    p = pge_world(cluster, "--out", str(out), "--set", "spin=0", "--adopt")
    assert p.returncode == 0, p.stderr
    assert "15 of 16 tiles already" in p.stderr, p.stderr
    world = read_world(str(out))
    assert world["complete"] is True and len(world["tiles"]) == 16
    assert tile_bytes(str(out), world) == shared
    for name, data in variants.items():
        assert (out / name).read_bytes() == data, name

    # A standalone tile among shared ones is refused, not adopted.
    other = tmp_path / "other"
    (other / "tiles").mkdir(parents=True)
    (other / "tiles" / "0_0.glb").write_bytes(reference[(0, 0)])
    p = pge_world(cluster, "--out", str(other), "--set", "spin=0", "--adopt")
    assert p.returncode == 1
    assert "0_0.glb: the tile carries its variants" in p.stderr, p.stderr
    assert p.stderr.count("\n") == 1, p.stderr
    assert not (other / "world.json").exists()


def test_a_folder_of_other_files_is_refused_and_left_as_it_was(cluster, tmp_path):
    out = tmp_path / "home"
    (out / "tiles").mkdir(parents=True)
    (out / "notes.txt").write_text("mine")
    (out / "tiles" / ".tmp-mine").write_text("mine too")
    p = pge_world(cluster, "--out", str(out))
    assert p.returncode == 1
    assert p.stderr.count("\n") == 1 and "not empty and not a world" in p.stderr, p.stderr
    assert sorted(str(f.relative_to(out)) for f in out.rglob("*")) == [
        "notes.txt",
        "tiles",
        "tiles/.tmp-mine",
    ]


def test_an_output_that_is_a_file_is_one_line(cluster, tmp_path):
    out = tmp_path / "taken"
    out.write_text("not a folder")
    p = pge_world(cluster, "--out", str(out))
    assert p.returncode == 1
    assert p.stderr.startswith("pge-world: ") and p.stderr.count("\n") == 1, p.stderr
    assert str(out) in p.stderr, p.stderr
    assert out.read_text() == "not a folder"
