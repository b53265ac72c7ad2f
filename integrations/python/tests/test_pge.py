"""The pge module against the pge command: same bytes, typed errors, the GIL and Ctrl-C.

Run from the repository root (``.ci/python`` does), with the ``pge`` binary built
(``target/debug/pge``, ``target/release/pge`` or ``$PGE``).
"""

from __future__ import annotations

import _thread
import json
import os
import subprocess
import threading
import time
from pathlib import Path

import pytest

import pge

ROOT = Path(__file__).resolve().parents[3]
RUNAWAY = "local t = {}\nwhile true do\n  t[1] = (t[1] or 0) + 1\nend\n"


def pge_binary() -> str:
    if os.environ.get("PGE"):
        return os.environ["PGE"]
    built = [ROOT / "target" / p / "pge" for p in ("debug", "release")]
    built = [p for p in built if p.exists()]
    if not built:
        pytest.fail("no pge binary: cargo build first, or set PGE")
    return str(max(built, key=lambda p: p.stat().st_mtime))


def pge_run(tmp_path: Path, script: str, *args: str) -> tuple[bytes, dict]:
    out = tmp_path / "out.glb"
    done = subprocess.run(
        [pge_binary(), "run", script, "-o", str(out), "--stats", "-q", *args],
        cwd=ROOT,
        capture_output=True,
        check=True,
    )
    return out.read_bytes(), json.loads(done.stdout)


@pytest.fixture(autouse=True)
def at_the_root(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)


def test_the_oak_is_the_bytes_pge_run_writes(tmp_path: Path) -> None:
    glb, stats = pge_run(tmp_path, "scripts/species/oak.lua")
    result = pge.generate("scripts/species/oak.lua")
    assert result.glb == glb
    assert isinstance(result.glb, bytes)
    for key in ("vertices", "triangles", "nodes", "leaves", "meshes", "instances"):
        assert result.stats[key] == stats[key], key
    assert result.warnings == []
    assert "output" not in result.stats


def test_params_seed_and_steps_are_pge_runs_flags(tmp_path: Path) -> None:
    glb, _ = pge_run(
        tmp_path, "scripts/examples/spiral.lua", "--set", "count=12", "--set",
        "radius=2.5", "--seed", "3",
    )
    result = pge.generate(
        "scripts/examples/spiral.lua", params={"count": 12, "radius": 2.5}, seed=3, threads=1
    )
    assert result.glb == glb
    other = pge.generate("scripts/examples/spiral.lua", params={"count": 12}, seed=3)
    assert other.glb != glb
    # The files to watch: the script and the module it requires.
    assert {Path(f).name for f in result.files} >= {"spiral.lua", "box.lua"}
    assert pge.library() == str(ROOT / "scripts")


def test_stages_are_scenes_of_one_glb(tmp_path: Path) -> None:
    glb, _ = pge_run(tmp_path, "scripts/lsystems/plants.lua", "--stages", "1,3")
    result = pge.generate(Path("scripts/lsystems/plants.lua"), stages=[1, 3])
    assert result.glb == glb
    assert [s["name"] for s in result.stats["stages"]] == ["step 1", "step 3"]


def test_a_script_error_names_the_file_and_line(tmp_path: Path) -> None:
    script = tmp_path / "bad.lua"
    script.write_text("local x = 1\nlocal y = nil + x\nreturn y\n")
    with pytest.raises(pge.ScriptError) as caught:
        pge.generate(script)
    e = caught.value
    assert (e.file, e.line) == (str(script), 2)
    assert "attempt to perform arithmetic" in e.message
    assert str(e) == f"{script}:2: {e.message}"
    assert type(e) is pge.ScriptError
    with pytest.raises(pge.ScriptError) as caught:
        pge.generate(source="return pge.model()\nerror('late')", name="editor/tree.lua")
    assert (caught.value.file, caught.value.line) == ("editor/tree.lua", 2)


def test_a_runaway_script_raises_time_limit() -> None:
    with pytest.raises(pge.TimeLimit) as caught:
        pge.generate(source=RUNAWAY, name="runaway.lua", time_limit=0.3)
    assert isinstance(caught.value, pge.ScriptError)
    assert caught.value.file == "runaway.lua"
    assert caught.value.line in (2, 3)
    with pytest.raises(pge.MemoryLimit):
        pge.generate(
            source="local t = {}\nfor i = 1, 1e9 do t[i] = {i} end", name="m.lua",
            memory_limit=16,
        )
    assert issubclass(pge.InstructionLimit, pge.ScriptError)


def test_bad_arguments_are_type_and_value_errors() -> None:
    spiral = "scripts/examples/spiral.lua"
    with pytest.raises(TypeError):
        pge.generate()
    with pytest.raises(TypeError):
        pge.generate(spiral, params=[("count", 3)])
    with pytest.raises(TypeError):
        pge.generate(spiral, params={"count": [3]})
    with pytest.raises(TypeError):
        pge.generate(spiral, seed="7")
    with pytest.raises(ValueError):
        pge.generate(spiral, seed=-1)
    with pytest.raises(ValueError):
        pge.generate(spiral, time_limit=0)
    with pytest.raises(ValueError):
        pge.generate(spiral, memory_limit=0)
    with pytest.raises(ValueError):
        pge.generate(spiral, threads=0)
    with pytest.raises(ValueError):
        pge.generate(spiral, source="return 1")
    with pytest.raises(ValueError):
        pge.generate(spiral, steps=3, stages=[1, 2])
    # A value outside a parameter's declared range is the script's error, as with --set.
    with pytest.raises(pge.ScriptError):
        pge.generate(spiral, params={"count": 0})


def test_params_and_tiles_describe_the_script() -> None:
    declared = pge.params("scripts/examples/spiral.lua")
    assert set(declared) == {"count", "turns", "radius", "rise", "jitter"}
    assert declared["count"] == {"default": 48, "min": 1, "max": 2000, "doc": "number of boxes"}
    assert declared["radius"]["default"] == 4.0
    tiles = pge.tiles("scripts/forests/plantation.lua")
    assert len(tiles) == 6
    assert {(t["i"], t["j"]) for t in tiles} == {(i, j) for i in range(3) for j in range(2)}
    assert tiles[0]["min"][0] < tiles[0]["max"][0]
    with pytest.raises(pge.ScriptError):
        pge.tiles("scripts/examples/spiral.lua")


def test_the_version_is_the_commands() -> None:
    done = subprocess.run([pge_binary(), "--version"], capture_output=True, check=True, text=True)
    assert done.stdout.split() == ["pge", pge.version]


def test_the_gil_is_released_while_generating() -> None:
    outcome: list[BaseException] = []

    def run() -> None:
        try:
            pge.generate(source=RUNAWAY, name="runaway.lua", time_limit=1.0)
        except pge.TimeLimit as e:
            outcome.append(e)

    worker = threading.Thread(target=run)
    worker.start()
    ticks = 0
    while worker.is_alive():
        ticks += 1
        time.sleep(0.01)
    worker.join()
    assert len(outcome) == 1
    # This thread ran Python all along: with the GIL held it would have ticked once or twice.
    assert ticks > 20


def test_ctrl_c_cancels_the_run_and_the_module_goes_on() -> None:
    # Ctrl-C as a user gives it: every half second until the run is over. (One interrupt
    # once failed CI on a loaded machine, the run going on to its time limit; that was not
    # reproduced since. The test still fails if no interrupt cancels the run.)
    stopped = threading.Event()

    def press() -> None:
        while not stopped.wait(0.5):
            _thread.interrupt_main()

    presser = threading.Thread(target=press)
    started = time.monotonic()
    presser.start()
    cancelled = False
    try:
        pge.generate(source=RUNAWAY, name="runaway.lua", time_limit=120)
    except KeyboardInterrupt:
        cancelled = True
    stopped.set()
    while True:
        # A press made just before the presser saw `stopped` is raised here, not later.
        try:
            presser.join()
            time.sleep(0.1)
            break
        except KeyboardInterrupt:
            continue
    assert cancelled, "the run was not cancelled"
    # Stopped by the interrupt, long before its time limit.
    assert time.monotonic() - started < 60
    assert pge.generate("scripts/examples/spiral.lua").glb[:4] == b"glTF"
