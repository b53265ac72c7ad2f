"""The run of ``pge-world``: from the options to a complete world directory.

The steps have their own modules: the tile list and the shared variants on this machine
(:mod:`.local`), what is kept of an earlier run (:mod:`.resume`), the batches
(:mod:`.plan`), the tasks (:mod:`.cluster`), the manifest (:mod:`.manifest`) and what the
run says (:mod:`.report`).
"""

from __future__ import annotations

import os
import shutil
import time
from pathlib import Path

from . import cluster, local, plan, resume
from . import manifest as mf
from .args import Options
from .errors import WorldError
from .records import Params, Tile, TileEntry, key
from .report import Clock, FinishedBatch, Progress, variants_line
from .tile import GrownTile, TileJob

#: Seconds between two writes of the manifest while tiles come back.
MANIFEST_EVERY = 2.0


def grow(opts: Options) -> int:
    """Grow the world of ``opts``: returns the exit status (errors raise)."""
    clock = Clock(opts.timings)
    script = Path(os.path.abspath(opts.script))
    if not script.is_file():
        raise WorldError(f"{opts.script}: no such script")
    opts.check()
    program = shutil.which(opts.pge)
    if program is None:
        raise WorldError(
            f"no `{opts.pge}` program on this machine's PATH: build pge "
            "(cargo build --release) and put it on the PATH, or pass --pge PATH"
        )
    overrides = opts.overrides
    ident = mf.identity(mf.sha256_file(script), opts.seed, overrides)
    out = Path(os.path.abspath(opts.out))
    old = mf.read(out) if out.is_dir() else None
    resume.refuse_other_world(old, ident, opts.out)
    shared = not opts.standalone_tiles
    variants_ok = shared and old is not None and mf.variants_intact(out, old)
    clock.mark("Python started, manifest read")

    # pge lists the tiles and writes the shared variants (on all this machine's cores) while
    # Ray is imported and connects; the tasks get the variants' description through the
    # object store, or read it from DIR on a shared folder.
    created = not out.exists()
    lister = local.start_tile_list(program, script, opts.seed, overrides)
    writer = None
    if shared and not variants_ok:
        out.mkdir(parents=True, exist_ok=True)
        writer = local.start_variants(program, script, opts.seed, overrides, opts.time_limit, out)
    connected = False
    progress = Progress(0, 0, opts.quiet)
    try:
        if resume.likely_work(old, shared, variants_ok):
            cluster.connect(opts.address)
            connected = True
            clock.mark("Ray imported and connected")
        tiles = local.tile_list(lister, script)
        clock.mark("pge tiles")
        progress.total = len(tiles)
        done = resume.kept_tiles(out, old, shared)
        params = old.get("params") if old is not None else None
        if opts.adopt:
            done, params = resume.adopt_all(out, tiles, done, opts.seed, overrides, params, shared)
        todo = [t for t in tiles if key(t) not in done]
        if todo and not connected:
            cluster.connect(opts.address)
            connected = True
            clock.mark("Ray imported and connected")
        # No warm-up task: it starts a worker of its own beside the tiles' (measured: the
        # extra Python processes on each node slowed the tiles more than they saved).
        nodes, on_this_machine = cluster.nodes() if connected else ([], True)
        variants = old.get("variants") if old is not None and variants_ok else None
        if writer is not None:
            waiting = time.monotonic()
            variants = local.finish_variants(writer, out)
            progress.later(variants_line(variants, time.monotonic() - waiting))
            clock.mark("variants written")
    except BaseException:
        local.stop([lister, writer])
        if created:
            # Nothing of this world was there before: leave nothing behind.
            shutil.rmtree(out, ignore_errors=True)
        raise
    if resume.variants_changed(old, shared, variants):
        done = {}
        todo = list(tiles)
    progress.done = progress.skipped = len(tiles) - len(todo)
    if done:
        progress.say(f"{len(done)} of {len(tiles)} tiles already in {opts.out}: skipped")
    if not todo:
        mf.write(out, ident, script, params or {}, done.values(), True, variants)
        if progress.note is not None:
            progress.say(progress.note)
        progress.say(f"world complete: {len(tiles)} tiles in {opts.out}, nothing to do")
        clock.mark("manifest written")
        clock.report()
        return 0
    if not connected:
        cluster.connect(opts.address)
        nodes, on_this_machine = cluster.nodes()
    shared_fs = on_this_machine if opts.shared_fs is None else opts.shared_fs
    (out / "tiles").mkdir(parents=True, exist_ok=True)
    variant_cache = opts.variant_cache and os.path.abspath(opts.variant_cache)
    job: TileJob = {
        "program": opts.pge,
        "script": script,
        "seed": opts.seed,
        "overrides": overrides,
        "threads": opts.cpus_per_tile,
        "time_limit": opts.time_limit,
        "variant_cache": None if opts.no_variant_cache or shared else variant_cache,
        "shared": shared,
        "out": out if shared_fs else None,
    }
    description = (out / mf.VARIANTS_JSON).read_bytes() if shared and not shared_fs else None
    slots = plan.slots((n.cpus for n in nodes), opts.cpus_per_tile)
    batches = plan.batches_of(todo, slots, opts.tiles_per_task)
    running = cluster.submit(job, opts.retries, description, batches)
    clock.mark(f"{len(running)} tasks of {len(todo)} tiles submitted")
    written = dict(done)
    finished: list[FinishedBatch] = []
    last_write = time.monotonic()
    try:
        while running:
            back = running.wait()
            for batch, result in back:
                finished.append(
                    FinishedBatch(
                        tiles=len(batch),
                        node=result["node"],
                        started=time.time() - result["seconds"],
                        seconds=result["seconds"],
                    )
                )
                bounds = {key(t): t for t in batch}
                for grown in result["tiles"]:
                    t = bounds[(grown["i"], grown["j"])]
                    written[key(t)] = save_tile(out, t, grown)
                    if params is None:
                        params = params_of(out, t, grown)
                    progress.tile(t["i"], t["j"])
                clock.mark(f"batch of {len(batch)} tiles back from {result['node']}")
            if back and time.monotonic() - last_write > MANIFEST_EVERY and running:
                mf.write(out, ident, script, params or {}, written.values(), False, variants)
                last_write = time.monotonic()
    except BaseException:
        running.cancel()
        if len(written) > len(done):
            mf.write(out, ident, script, params or {}, written.values(), False, variants)
        raise
    mf.write(out, ident, script, params or {}, written.values(), True, variants)
    mf.clean_scratch(out / "tiles")
    clock.mark("manifest written")
    total = sum(e["instances"] for e in written.values())
    elapsed = time.monotonic() - progress.start
    progress.say(
        f"world complete: {len(tiles)} tiles, {total} instances in {opts.out} ({elapsed:.1f}s)"
    )
    clock.report(finished)
    return 0


def save_tile(out: Path, tile: Tile, grown: GrownTile) -> TileEntry:
    """Return the manifest entry of a tile a task grew, its file written when the task sent it.

    A task that sees the world directory (a shared folder) wrote the file itself and sent
    its hash; otherwise the file is written here, atomically.
    """
    data = grown.get("glb")
    if data is not None:
        mf.write_atomically(out / mf.tile_file(tile["i"], tile["j"]), data)
    return mf.tile_entry(tile, grown["sha256"], grown["bytes"], grown["instances"])


def params_of(out: Path, tile: Tile, grown: GrownTile) -> Params:
    """Return the declared parameters' values, from a tile's ``extras.pge.params``."""
    data = grown.get("glb")
    if data is None:
        data = (out / mf.tile_file(tile["i"], tile["j"])).read_bytes()
    return mf.tile_params(data)
