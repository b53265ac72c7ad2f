"""The run of ``pge-world``: from the options to a complete world directory.

The steps have their own modules: the world directory and its manifest, kept by ``pge
world`` (:mod:`.manifest`), the tile list and the shared variants on this machine
(:mod:`.local`), the batches (:mod:`.plan`), the tasks (:mod:`.cluster`) and what the run
says (:mod:`.report`).
"""

from __future__ import annotations

import os
import shutil
import time
from pathlib import Path

from . import cluster, local, plan
from . import manifest as mf
from .args import Options
from .errors import WorldError
from .records import TileKey, key
from .report import Clock, FinishedBatch, Progress, variants_line
from .tile import GrownTile, TileJob


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
    out = Path(os.path.abspath(opts.out))
    shared = not opts.standalone_tiles
    # pge opens the directory first: another world's, or a folder of other files, is
    # refused before anything runs or is written.
    opened = mf.init(program, script, opts.seed, overrides, out, shared)
    variants_ok = shared and opened.variants
    clock.mark("Python started, world directory opened")

    # pge lists the tiles and writes the shared variants (on all this machine's cores) while
    # Ray is imported and connects; the tasks get the variants' description through the
    # object store, or read it from DIR on a shared folder.
    lister = writer = None
    connected = False
    progress = Progress(0, 0, opts.quiet)
    try:
        lister = local.start_tile_list(program, script, opts.seed, overrides)
        if shared and not variants_ok:
            writer = local.start_variants(
                program, script, opts.seed, overrides, opts.time_limit, out
            )
        if likely_work(opened, shared):
            cluster.connect(opts.address)
            connected = True
            clock.mark("Ray imported and connected")
        tiles = local.tile_list(lister, script)
        clock.mark("pge tiles")
        progress.total = len(tiles)
        done = set(opened.tiles)
        if writer is not None:
            waiting = time.monotonic()
            local.finish_variants(writer)
            changed, variants = mf.record_variants(program, out)
            if changed:
                done = set()
            progress.later(variants_line(variants, time.monotonic() - waiting))
            clock.mark("variants written")
        if opts.adopt:
            done |= set(mf.adopt(program, out))
        todo = [t for t in tiles if key(t) not in done]
        if todo and not connected:
            cluster.connect(opts.address)
            connected = True
            clock.mark("Ray imported and connected")
        # No warm-up task: it starts a worker of its own beside the tiles' (measured: the
        # extra Python processes on each node slowed the tiles more than they saved).
        nodes, on_this_machine = cluster.nodes() if connected else ([], True)
    except BaseException:
        local.stop([lister, writer])
        # Nothing grown: leave the folder as it was (no manifest where there was none).
        mf.forget(out, opened)
        raise
    progress.done = progress.skipped = len(tiles) - len(todo)
    if done:
        progress.say(
            f"{len(tiles) - len(todo)} of {len(tiles)} tiles already in {opts.out}: skipped"
        )
    if not todo:
        mf.finish(program, out)
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
    finished: list[FinishedBatch] = []
    recorded = False
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
                grown = [save_tile(out, g) for g in result["tiles"]]
                mf.add(program, out, grown)
                recorded = True
                for i, j in grown:
                    progress.tile(i, j)
                clock.mark(f"batch of {len(batch)} tiles back from {result['node']}")
    except BaseException:
        running.cancel()
        if not recorded:
            mf.forget(out, opened)
        raise
    total = mf.finish(program, out)
    clock.mark("manifest written")
    elapsed = time.monotonic() - progress.start
    progress.say(
        f"world complete: {len(tiles)} tiles, {total} instances in {opts.out} ({elapsed:.1f}s)"
    )
    clock.report(finished)
    return 0


def likely_work(opened: mf.Opened, shared: bool) -> bool:
    """Whether a run likely grows something, so connects to Ray at once.

    A complete world with intact variants is checked first, without Ray.
    """
    return not opened.complete or (shared and not opened.variants)


def save_tile(out: Path, grown: GrownTile) -> TileKey:
    """Return the index of a tile a task grew, its file written here when the task sent it.

    A task that sees the world directory (a shared folder) wrote the file itself; otherwise
    its bytes came back and are written here, atomically. ``pge world add`` then records it.
    """
    i, j = grown["i"], grown["j"]
    data = grown.get("glb")
    if data is not None:
        mf.write_atomically(out / mf.tile_file(i, j), data)
    return (i, j)
