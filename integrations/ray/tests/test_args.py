"""The command line and the errors a run reports before it needs a cluster."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import FakePge

from pge_world import cli, local, world
from pge_world import manifest as mf
from pge_world.args import Options, parse
from pge_world.errors import WorldError
from pge_world.tile import GrownTile

pytestmark = pytest.mark.unit


def test_the_defaults() -> None:
    assert parse(["forest.lua", "--out", "world"]) == Options(script="forest.lua", out="world")


def test_every_option() -> None:
    opts = parse(
        [
            "f.lua",
            "--out=w",
            "--address",
            "head:6379",
            "--set",
            "spin = 3",
            "--set",
            "name=a=b",
            "--seed",
            "9",
            "--pge",
            "/opt/pge",
            "--cpus-per-tile",
            "2",
            "--retries",
            "0",
            "--time-limit",
            "1.5",
            "--standalone-tiles",
            "--variant-cache",
            "/c",
            "--no-variant-cache",
            "--adopt",
            "--no-shared-fs",
            "--tiles-per-task",
            "4",
            "--timings",
            "-q",
        ]
    )
    assert opts == Options(
        script="f.lua",
        out="w",
        address="head:6379",
        overrides=(("spin", " 3"), ("name", "a=b")),
        seed=9,
        pge="/opt/pge",
        cpus_per_tile=2,
        retries=0,
        time_limit=1.5,
        standalone_tiles=True,
        variant_cache="/c",
        no_variant_cache=True,
        adopt=True,
        shared_fs=False,
        tiles_per_task=4,
        timings=True,
        quiet=True,
    )
    assert parse(["f.lua", "--out", "w", "--shared-fs"]).shared_fs is True


@pytest.mark.parametrize(
    "argv, message",
    [
        (["f.lua", "--out", "w", "--set", "spin"], "'spin' is not NAME=VALUE"),
        (["f.lua", "--out", "w", "--set", " =3"], "' =3' is not NAME=VALUE"),
        (["f.lua"], "the following arguments are required: --out"),
        (["--out", "w"], "the following arguments are required: script"),
        (["f.lua", "--out", "w", "--seed", "x"], "argument --seed: invalid int value: 'x'"),
        (["f.lua", "--out", "w", "--frobnicate"], "unrecognized arguments: --frobnicate"),
    ],
)
def test_usage_errors_exit_2(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as e:
        cli.main(argv)
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: pge-world") and message in err, err


@pytest.mark.parametrize(
    "changes",
    [{"cpus_per_tile": 0}, {"retries": -1}, {"tiles_per_task": -2}],
)
def test_numbers_out_of_range_are_refused(changes: dict[str, int]) -> None:
    Options(script="f.lua", out="w").check()
    with pytest.raises(WorldError) as e:
        Options(script="f.lua", out="w", **changes).check()  # type: ignore[arg-type]
    assert "--cpus-per-tile must be at least 1" in str(e.value)


def run_cli(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    status = cli.main(argv)
    return status, capsys.readouterr().err


def test_a_missing_script_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    status, err = run_cli(["missing.lua", "--out", str(tmp_path / "w")], capsys)
    assert (status, err) == (1, "pge-world: missing.lua: no such script\n")
    assert not (tmp_path / "w").exists()


def test_errors_before_any_work_are_one_line(
    tmp_path: Path, fake_pge: FakePge, capsys: pytest.CaptureFixture[str]
) -> None:
    script = tmp_path / "forest.lua"
    script.write_text("return forest\n")
    out = tmp_path / "w"
    base = [str(script), "--out", str(out)]
    status, err = run_cli([*base, "--cpus-per-tile", "0"], capsys)
    assert status == 1
    assert err == (
        "pge-world: --cpus-per-tile must be at least 1, --retries and --tiles-per-task at least 0\n"
    )
    status, err = run_cli([*base, "--pge", "no-such-pge-here"], capsys)
    assert status == 1
    assert err == (
        "pge-world: no `no-such-pge-here` program on this machine's PATH: build pge "
        "(cargo build --release) and put it on the PATH, or pass --pge PATH\n"
    )
    # pge world refuses the directory (another world's, a folder of other files): one
    # line, and nothing else runs.
    refusal = f"{out} holds another world (script /a.lua, seed 2, set {{}}): choose another"
    status, err = run_cli([*base, "--pge", fake_pge.path, "--set", f"fail={refusal}"], capsys)
    assert (status, err) == (1, f"pge-world: {refusal}\n")
    assert [c[:2] for c in fake_pge.calls()] == [["world", "init"]]


def test_the_tile_list_and_the_variants_come_from_pge(tmp_path: Path, fake_pge: FakePge) -> None:
    script = Path("/w/forest.lua")
    lister = local.start_tile_list(fake_pge.path, script, 5, [("spin", "1")])
    assert local.tile_list(lister, script) == [
        {"i": 0, "j": 0, "min": [0, 0], "max": [1, 1]},
        {"i": 1, "j": 0, "min": [1, 0], "max": [2, 1]},
    ]
    writer = local.start_variants(fake_pge.path, script, 5, [], 3.0, tmp_path)
    local.finish_variants(writer)
    assert (tmp_path / "variants.bin").read_text() == "variants.bin of seed 5"
    tiles_call, variants_call = fake_pge.calls()
    assert tiles_call == ["tiles", "/w/forest.lua", "--seed", "5", "--set", "spin=1"]
    assert variants_call == [
        "run",
        "/w/forest.lua",
        "--seed",
        "5",
        "--time-limit",
        "3.0",
        "--variants-out",
        str(tmp_path),
        "-q",
    ]


def test_pges_errors_on_this_machine_are_its_last_line(tmp_path: Path, fake_pge: FakePge) -> None:
    script = Path("/w/forest.lua")
    failing = [("fail", "forest.lua: pge tiles needs a script that returns a forest")]
    lister = local.start_tile_list(fake_pge.path, script, 1, failing)
    with pytest.raises(WorldError) as e:
        local.tile_list(lister, script)
    assert str(e.value) == "forest.lua: pge tiles needs a script that returns a forest"
    writer = local.start_variants(
        fake_pge.path, script, 1, [("fail", "x.lua:3: oops")], None, tmp_path
    )
    with pytest.raises(WorldError) as e:
        local.finish_variants(writer)
    assert str(e.value) == "variants: x.lua:3: oops"
    with pytest.raises(WorldError) as e:
        local.start_tile_list(str(tmp_path / "nothing"), script, 1, [])
    assert str(e.value).startswith(f"cannot run {tmp_path / 'nothing'}: ")


def test_a_tile_sent_back_is_written_here(tmp_path: Path) -> None:
    (tmp_path / "tiles").mkdir()
    sent: GrownTile = {"i": 1, "j": 2, "glb": b"the tile"}
    assert world.save_tile(tmp_path, sent) == (1, 2)
    assert (tmp_path / "tiles" / "1_2.glb").read_bytes() == b"the tile"
    # A task that wrote the tile itself sent only its index: the file is not touched.
    (tmp_path / "tiles" / "1_2.glb").write_bytes(b"written by the task")
    assert world.save_tile(tmp_path, {"i": 1, "j": 2}) == (1, 2)
    assert (tmp_path / "tiles" / "1_2.glb").read_bytes() == b"written by the task"


def test_only_a_complete_world_with_intact_variants_waits_to_connect() -> None:
    def opened(complete: bool, variants: bool) -> mf.Opened:
        return mf.Opened(False, False, complete=complete, variants=variants, tiles=frozenset())

    assert not world.likely_work(opened(True, True), shared=True)
    assert not world.likely_work(opened(True, False), shared=False)
    assert world.likely_work(opened(True, False), shared=True)
    assert world.likely_work(opened(False, True), shared=True)
