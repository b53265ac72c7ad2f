"""``pge-world SCRIPT --out DIR``: one Ray task per tile of a forest, a world directory.

Errors the user can fix (no cluster, another world in DIR, a script without ``tile``, a
script error in a tile, no ``pge`` on a worker) end with one line on stderr and exit
status 1; usage errors exit 2 (argparse).
"""

import argparse
import ipaddress
import json
import os
import shutil
import socket
import subprocess
import sys
import time

from . import manifest as mf
from .manifest import WorldError
from .tile import TileFailed, grow_tile, last_line, pge_args


def parse_set(text):
    """``NAME=VALUE`` as a pair (an argparse type)."""
    name, sep, value = text.partition("=")
    if not sep or not name.strip():
        raise argparse.ArgumentTypeError(f"'{text}' is not NAME=VALUE")
    return (name.strip(), value)


def parser():
    """The command line of ``pge-world``."""
    p = argparse.ArgumentParser(
        prog="pge-world",
        description="Grow a PGE forest (a script with tile = T) tile by tile on a Ray "
        "cluster: one task per tile, written to DIR/tiles/I_J.glb with the manifest "
        "DIR/world.json. Running again on the same DIR resumes: tiles already written "
        "are skipped.",
    )
    p.add_argument("script", help="the forest script (pge.Forest with tile = T)")
    p.add_argument("--out", required=True, metavar="DIR", help="the world directory")
    p.add_argument(
        "--address",
        metavar="ADDR",
        help="the Ray cluster (HOST:PORT of its head, or 'auto'); default: the cluster "
        "started on this machine with `ray start`, else a new one on this machine",
    )
    p.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        type=parse_set,
        metavar="NAME=VALUE",
        help="override a parameter declared with pge.params (repeatable)",
    )
    p.add_argument("--seed", type=int, default=1, help="seed of every random draw (default 1)")
    p.add_argument(
        "--pge",
        default="pge",
        metavar="PROGRAM",
        help="the pge program: a name looked up on the PATH (here and on every worker) "
        "or a path that exists on every machine (default: pge)",
    )
    p.add_argument(
        "--cpus-per-tile",
        type=int,
        default=1,
        metavar="N",
        help="CPUs each tile task reserves and pge threads it uses (default 1)",
    )
    p.add_argument(
        "--retries",
        type=int,
        default=3,
        metavar="N",
        help="times a tile is run again after its worker or machine died (default 3)",
    )
    p.add_argument(
        "--time-limit",
        type=float,
        metavar="SECONDS",
        help="pge's --time-limit for every tile (default: pge's own)",
    )
    p.add_argument(
        "--standalone-tiles",
        action="store_true",
        help="every tile carries the variant meshes it places (a glb of its own, ~30 MB for "
        "big.lua) instead of referring to DIR/variants.bin, the variants written once on this "
        "machine (the default)",
    )
    p.add_argument(
        "--variant-cache",
        default="",
        metavar="DIR",
        help="with --standalone-tiles, pge's --variant-cache on every worker: the folder where "
        "the tiles of a machine share the species variants they grow (a path that exists on every machine, local "
        "or shared); default: pge-variants-USER in each machine's temporary folder",
    )
    p.add_argument(
        "--no-variant-cache",
        action="store_true",
        help="every tile grows every variant itself",
    )
    p.add_argument(
        "--adopt",
        action="store_true",
        help="take tile files already in DIR/tiles that the manifest does not list (written "
        "by a Kubernetes Indexed Job or a Slurm array) when their seed, parameters and tile "
        "index match this run",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress")
    return p


class Progress:
    """Tiles done / total, rate and ETA on stderr: one line rewritten on a terminal, a line
    per tile otherwise."""

    def __init__(self, total, skipped, quiet):
        self.total = total
        self.done = skipped
        self.skipped = skipped
        self.quiet = quiet
        self.start = time.monotonic()
        self.tty = sys.stderr.isatty()
        self.note = None

    def later(self, line):
        """A line said with the first tile written (a run that fails before says only its
        error)."""
        self.note = line

    def tile(self, i, j):
        """Tile (i, j) has been written."""
        self.done += 1
        if self.quiet:
            return
        if self.note is not None:
            sys.stderr.write(self.note + "\n")
            self.note = None
        grown = self.done - self.skipped
        elapsed = time.monotonic() - self.start
        rate = grown / elapsed if elapsed > 0 else 0.0
        left = self.total - self.done
        eta = f"{left / rate:.0f}s" if rate > 0 else "?"
        line = (
            f"tiles {self.done}/{self.total} (tile {i},{j}) "
            f"{rate:.2f} tiles/s, {elapsed:.0f}s elapsed, ETA {eta}"
        )
        if self.tty:
            sys.stderr.write("\r\033[K" + line + ("\n" if left == 0 else ""))
        else:
            sys.stderr.write(line + "\n")
        sys.stderr.flush()

    def say(self, line):
        """A line of its own."""
        if not self.quiet:
            sys.stderr.write(line + "\n")
            sys.stderr.flush()


def tile_list(program, script, seed, overrides):
    """``pge tiles SCRIPT`` run on this machine: the list of tiles, or its error line."""
    try:
        proc = subprocess.run(
            [program, "tiles"] + pge_args(script, seed, overrides),
            stdin=subprocess.DEVNULL,
            capture_output=True,
            text=True,
        )
    except OSError as e:
        raise WorldError(f"cannot run {program}: {e}") from e
    if proc.returncode != 0:
        raise WorldError(last_line(proc.stderr) or f"pge tiles exited with {proc.returncode}")
    try:
        tiles = json.loads(proc.stdout)
    except ValueError as e:
        raise WorldError(f"pge tiles printed no tile list: {e}") from e
    if not tiles:
        raise WorldError(f"{script}: the forest has no tiles")
    return tiles


def reachable(address):
    """Fails at once when nothing listens at HOST:PORT (Ray itself would retry for
    minutes)."""
    host, sep, port = address.rpartition(":")
    if not sep or not port.isdigit():
        raise WorldError(f"--address {address} is not HOST:PORT (the head's GCS port, 6379)")
    host = host.removeprefix("ray://").strip("[]")
    try:
        socket.create_connection((host, int(port)), timeout=10).close()
    except OSError as e:
        raise WorldError(
            f"no Ray cluster at {address} ({e.strerror or e}); start one with "
            "`ray start --head` and pass its address with --address"
        ) from e


def connect(address):
    """Connects to the Ray cluster at ``address`` (None: this machine's), or says what to
    do."""
    import ray

    # The first failed tile ends the run; the others' errors are not news.
    os.environ.setdefault("RAY_IGNORE_UNHANDLED_ERRORS", "1")
    kwargs = {"logging_level": "ERROR", "log_to_driver": False}
    if address is None:
        kwargs["include_dashboard"] = False
    else:
        kwargs["address"] = address
        host = address.rsplit(":", 1)[0] if ":" in address else address
        try:
            if ipaddress.ip_address(host).is_loopback:
                # A cluster on this machine's loopback: the driver's node is that address.
                kwargs["_node_ip_address"] = host
        except ValueError:
            pass
    if address is not None and address != "auto":
        reachable(address)
    try:
        ray.init(**kwargs)
    except Exception as e:  # Ray raises several types for an unreachable cluster.
        where = f"at {address}" if address else "on this machine"
        reason = last_line(str(e)) or type(e).__name__
        raise WorldError(
            f"no Ray cluster {where} ({reason}); start one with `ray start --head` "
            "and pass its address with --address"
        ) from e
    return ray


def grow(args):
    """The run: returns the exit status."""
    script = os.path.abspath(args.script)
    if not os.path.isfile(script):
        raise WorldError(f"{args.script}: no such script")
    if args.cpus_per_tile < 1 or args.retries < 0:
        raise WorldError("--cpus-per-tile must be at least 1 and --retries at least 0")
    program = shutil.which(args.pge)
    if program is None:
        raise WorldError(
            f"no `{args.pge}` program on this machine's PATH: build pge "
            "(cargo build --release) and put it on the PATH, or pass --pge PATH"
        )
    overrides = [tuple(o) for o in args.overrides]
    ident = mf.identity(mf.sha256_file(script), args.seed, overrides)
    out = os.path.abspath(args.out)
    old = mf.read(out) if os.path.isdir(out) else None
    if old is not None and not mf.same_world(old, ident):
        raise WorldError(
            f"{args.out} holds another world (script {old.get('script')}, seed "
            f"{old.get('seed')}, set {old.get('set')}): choose another --out or delete it"
        )
    tiles = tile_list(program, script, args.seed, overrides)
    shared = not args.standalone_tiles
    done = mf.done_tiles(out, old) if old is not None else {}
    if old is not None and (old.get("variants") is not None) != shared:
        # Tiles of the other form (standalone or referring to shared variants): grown again.
        done = {}
    params = old.get("params") if old is not None else None
    if args.adopt:
        for t in tiles:
            if (t["i"], t["j"]) not in done:
                entry, tile_params = adopt(out, t, args.seed, overrides, params)
                if entry is not None:
                    done[(t["i"], t["j"])] = entry
                    params = tile_params
    variants_ok = shared and old is not None and mf.variants_intact(out, old)
    todo = [t for t in tiles if (t["i"], t["j"]) not in done]
    progress = Progress(len(tiles), 0, args.quiet)
    variants = old.get("variants") if variants_ok else None
    if not todo and (variants_ok or not shared):
        progress.say(f"{len(done)} of {len(tiles)} tiles already in {args.out}: skipped")
        mf.write(out, ident, script, params or {}, list(done.values()), True, variants)
        progress.say(f"world complete: {len(tiles)} tiles in {args.out}, nothing to do")
        return 0

    # The shared variants are written once, on this machine on all its cores, while Ray
    # connects; the tasks get their description (not the meshes) through the object store.
    writer = None
    created = not os.path.exists(out)
    if shared and not variants_ok:
        os.makedirs(out, exist_ok=True)
        writer = start_variants(program, script, args, overrides, out)
    ray = None
    try:
        if todo:
            ray = connect(args.address)
        if writer is not None:
            variants = finish_variants(writer, out, progress)
    except BaseException:
        if writer is not None and writer.poll() is None:
            writer.kill()
            writer.wait()
        if created:
            # Nothing of this world was there before: leave nothing behind.
            shutil.rmtree(out, ignore_errors=True)
        raise
    recorded = old.get("variants") if old is not None else None
    if shared and recorded is not None and recorded != variants:
        # Other variants (another pge): every tile refers to them, every tile grows again.
        done = {}
        todo = list(tiles)
    progress.done = progress.skipped = len(tiles) - len(todo)
    if done:
        progress.say(f"{len(done)} of {len(tiles)} tiles already in {args.out}: skipped")
    if not todo:
        mf.write(out, ident, script, params or {}, list(done.values()), True, variants)
        if progress.note is not None:
            progress.say(progress.note)
        progress.say(f"world complete: {len(tiles)} tiles in {args.out}, nothing to do")
        return 0
    if ray is None:
        ray = connect(args.address)
    from ray import cloudpickle

    from . import tile as tile_module

    # Ship the task's code with it: workers need Ray and pge, not this package.
    cloudpickle.register_pickle_by_value(tile_module)
    os.makedirs(os.path.join(out, "tiles"), exist_ok=True)
    task = ray.remote(grow_tile).options(
        num_cpus=args.cpus_per_tile,
        max_retries=args.retries,
        retry_exceptions=False,
        scheduling_strategy="SPREAD",
    )
    variant_cache = args.variant_cache and os.path.abspath(args.variant_cache)
    if args.no_variant_cache or shared:
        variant_cache = None
    description = None
    if shared:
        with open(os.path.join(out, mf.VARIANTS_JSON), "rb") as f:
            description = ray.put(f.read())
    pending = {}
    for t in todo:
        ref = task.remote(
            args.pge, script, args.seed, overrides, t["i"], t["j"], args.cpus_per_tile,
            args.time_limit, variant_cache, description,
        )
        pending[ref] = t
    written = dict(done)
    last_write = time.monotonic()
    try:
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1, timeout=1.0)
            for ref in ready:
                t = pending.pop(ref)
                result = fetch(ray, ref, t)
                entry = save_tile(out, t, result)
                written[(t["i"], t["j"])] = entry
                if params is None:
                    params = mf.glb_root_extras(result["glb"]).get("params", {})
                progress.tile(t["i"], t["j"])
            if ready and time.monotonic() - last_write > 2.0 and pending:
                mf.write(out, ident, script, params, list(written.values()), False, variants)
                last_write = time.monotonic()
    except BaseException:
        for ref in pending:
            ray.cancel(ref, force=True)
        if len(written) > len(done):
            mf.write(out, ident, script, params or {}, list(written.values()), False, variants)
        raise
    mf.write(out, ident, script, params, list(written.values()), True, variants)
    total = sum(e["instances"] for e in written.values())
    elapsed = time.monotonic() - progress.start
    progress.say(
        f"world complete: {len(tiles)} tiles, {total} instances in {args.out} ({elapsed:.1f}s)"
    )
    return 0


def start_variants(program, script, args, overrides, out):
    """Starts ``pge run SCRIPT --variants-out DIR`` on this machine (every core)."""
    cmd = [program, "run"] + pge_args(script, args.seed, overrides, args.time_limit)
    cmd += ["--variants-out", out, "-q"]
    try:
        return subprocess.Popen(
            cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
            text=True,
        )
    except OSError as e:
        raise WorldError(f"cannot run {program}: {e}") from e


def finish_variants(writer, out, progress):
    """Waits for :func:`start_variants`; the manifest's record of the variants, or the
    error line of pge."""
    start = time.monotonic()
    _, err = writer.communicate()
    if writer.returncode != 0:
        message = last_line(err) or f"pge exited with status {writer.returncode}"
        raise WorldError(f"variants: {message}")
    entry = mf.variants_entry(out)
    if entry is None:
        raise WorldError(f"variants: pge wrote no {mf.VARIANTS_JSON} in {out}")
    progress.later(
        f"variants: {entry['bytes'] / 1e6:.1f} MB in {mf.VARIANTS_BIN}, written once "
        f"(waited {time.monotonic() - start:.1f}s for them after connecting)"
    )
    return entry


def matches(value, text):
    """Whether a parameter's recorded ``value`` is what ``--set NAME=text`` gives."""
    if isinstance(value, bool):
        return text.strip().lower() == json.dumps(value)
    if isinstance(value, (int, float)):
        try:
            return float(text) == value
        except ValueError:
            return False
    return value == text


def adopt(out, t, seed, overrides, params):
    """The manifest entry and parameters of tile ``t``'s file in ``out`` when it was written
    by ``pge run --tile`` with this seed and these settings; (None, None) when there is no
    file; an error when it belongs to another run."""
    name = mf.tile_file(t["i"], t["j"])
    path = os.path.join(out, name)
    try:
        with open(path, "rb") as f:
            data = f.read()
    except FileNotFoundError:
        return None, None
    except OSError as e:
        raise WorldError(f"{path}: {e}") from e
    try:
        extras = mf.glb_root_extras(data)
    except (WorldError, ValueError) as e:
        raise WorldError(f"{path}: not a tile ({e}); delete it to grow it again") from e
    forest = extras.get("forest") or {}
    tile_params = extras.get("params") or {}
    same = (
        forest.get("tileIndex") == [t["i"], t["j"]]
        and extras.get("seed") == seed
        and all(matches(tile_params.get(k), v) for k, v in overrides)
        and (params is None or tile_params == params)
    )
    if not same:
        raise WorldError(
            f"{path}: written with another seed, parameters or tile; delete it to grow it "
            "again, or choose another --out"
        )
    entry = {
        "i": t["i"],
        "j": t["j"],
        "min": t["min"],
        "max": t["max"],
        "file": name,
        "sha256": mf.sha256_bytes(data),
        "bytes": len(data),
        "instances": int(forest.get("instances", 0)),
    }
    return entry, tile_params


def fetch(ray, ref, t):
    """The result of a tile task, or a one-line error naming the tile."""
    from ray.exceptions import RayError, RayTaskError

    try:
        return ray.get(ref)
    except RayTaskError as e:
        cause = getattr(e, "cause", None)
        # The task's module travels by value (workers need only Ray and pge), so its
        # exception class is a copy: compare by name.
        if type(cause).__name__ == TileFailed.__name__:
            raise WorldError(f"tile {t['i']},{t['j']}: {cause}") from None
        reason = last_line(str(cause if cause is not None else e))
        raise WorldError(f"tile {t['i']},{t['j']} failed: {reason}") from None
    except RayError as e:
        raise WorldError(
            f"tile {t['i']},{t['j']} failed after {type(e).__name__}: {last_line(str(e))}"
        ) from None


def save_tile(out, t, result):
    """Writes a tile's file atomically and returns its manifest entry."""
    name = mf.tile_file(t["i"], t["j"])
    mf.write_atomically(os.path.join(out, name), result["glb"])
    return {
        "i": t["i"],
        "j": t["j"],
        "min": t["min"],
        "max": t["max"],
        "file": name,
        "sha256": mf.sha256_bytes(result["glb"]),
        "bytes": len(result["glb"]),
        "instances": result["instances"],
    }


def main(argv=None):
    """The console script: exit status 0, 1 (a problem to fix) or 2 (usage)."""
    args = parser().parse_args(argv)
    try:
        return grow(args)
    except WorldError as e:
        sys.stderr.write(f"pge-world: {e}\n")
        return 1
    except OSError as e:  # writing the world: a full disk, a file where DIR should be
        where = f"{e.filename}: " if e.filename else ""
        sys.stderr.write(f"pge-world: {where}{e.strerror or e}\n")
        return 1
    except KeyboardInterrupt:
        sys.stderr.write("pge-world: interrupted; run again on the same --out to resume\n")
        return 130


if __name__ == "__main__":
    sys.exit(main())
