"""``pge-world SCRIPT --out DIR``: a forest grown on a Ray cluster in batches of tiles (one
task and one ``pge`` process each), a world directory.

Errors the user can fix (no cluster, another world in DIR, a script without ``tile``, a
script error in a tile, no ``pge`` on a worker) end with one line on stderr and exit
status 1; usage errors exit 2 (argparse).
"""

import time

# When this process started, for --timings (Python's own start and imports included).
_IMPORTED = time.time()

import argparse  # noqa: E402 (after the clock)
import json  # noqa: E402
import os  # noqa: E402
import shutil  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402

from . import manifest as mf  # noqa: E402
from .manifest import WorldError  # noqa: E402
from .tile import TileFailed, grow_tiles, last_line, pge_args  # noqa: E402


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
        "cluster, in batches (one task and one pge process each), written to "
        "DIR/tiles/I_J.glb with the manifest "
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
    p.add_argument(
        "--shared-fs",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="the workers see DIR at the same path (one machine, or a shared folder): the "
        "tasks write the tiles there themselves and return only their hashes, instead of "
        "sending the bytes to this machine; default: on when every node of the cluster is "
        "this machine",
    )
    p.add_argument(
        "--tiles-per-task",
        type=int,
        default=0,
        metavar="N",
        help="tiles one task grows with one pge process (default: the tiles spread evenly "
        "over the cluster's CPUs, one task each, at most 16 tiles a task)",
    )
    p.add_argument(
        "--timings",
        action="store_true",
        help="print when each phase of the run ended, in seconds since this process started",
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


class Clock:
    """When each phase of the run ended (``--timings``), in seconds since the process
    started (Linux: the kernel's start time, so Python's start and imports count)."""

    def __init__(self, on):
        self.on = on
        self.start = _process_start()
        self.marks = []

    def mark(self, phase):
        """Phase ``phase`` has just ended."""
        self.marks.append((phase, time.time() - self.start))

    def report(self, batches=()):
        """The phases and the batches' own times on stderr."""
        if not self.on:
            return
        lines = [f"  {t:6.2f}s  {phase}" for phase, t in self.marks]
        for b in batches:
            lines.append(
                f"  batch of {len(b['tiles'])} tiles on {b['node']}: started at "
                f"{b['started'] - self.start:.2f}s, {b['seconds']:.2f}s in the task"
            )
        sys.stderr.write("timings (seconds since the process started):\n")
        sys.stderr.write("\n".join(lines) + "\n")


def _process_start():
    """This process's start as a Unix time: from /proc on Linux, else when this module was
    imported. The age comes from the system's uptime (hundredths of a second), not from
    /proc/stat's boot time, which is rounded to the second and put the start up to a second
    early."""
    try:
        with open("/proc/self/stat", encoding="ascii") as f:
            ticks = int(f.read().rsplit(")", 1)[1].split()[19])
        with open("/proc/uptime", encoding="ascii") as f:
            uptime = float(f.read().split()[0])
        age = uptime - ticks / os.sysconf("SC_CLK_TCK")
        return time.time() - max(age, 0.0)
    except (OSError, ValueError, IndexError):
        return _IMPORTED


def start_tile_list(program, script, seed, overrides):
    """Starts ``pge tiles SCRIPT`` on this machine (:func:`tile_list` reads it)."""
    try:
        return subprocess.Popen(
            [program, "tiles"] + pge_args(script, seed, overrides),
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
    except OSError as e:
        raise WorldError(f"cannot run {program}: {e}") from e


def tile_list(lister, script):
    """The list of tiles ``pge tiles`` printed, or its error line."""
    stdout, stderr = lister.communicate()
    if lister.returncode != 0:
        raise WorldError(last_line(stderr) or f"pge tiles exited with {lister.returncode}")
    try:
        tiles = json.loads(stdout)
    except ValueError as e:
        raise WorldError(f"pge tiles printed no tile list: {e}") from e
    if not tiles:
        raise WorldError(f"{script}: the forest has no tiles")
    return tiles


def reachable(address):
    """Fails at once when nothing listens at HOST:PORT (Ray itself would retry for
    minutes)."""
    import socket

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
    import ipaddress

    if address is not None and address != "auto":
        reachable(address)
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


def cluster_nodes(ray):
    """The alive nodes that have CPUs: ``[(node id, address, CPUs)]``, and whether they are
    all this machine (the driver's address)."""
    here = ray.get_runtime_context().get_node_id()
    nodes = [n for n in ray.nodes() if n.get("Alive")]
    mine = next((n["NodeManagerAddress"] for n in nodes if n["NodeID"] == here), None)
    working = [
        (n["NodeID"], n["NodeManagerAddress"], int(n.get("Resources", {}).get("CPU", 0)))
        for n in nodes
    ]
    working = [w for w in working if w[2] > 0]
    return working, all(addr == mine for _, addr, _ in working)


# The most tiles a task grows by default: enough to spread pge's start over many tiles, few
# enough that progress, load balance and a retried task stay fine-grained on a small cluster.
MAX_TILES_PER_TASK = 16


def batches_of(todo, slots, per_task):
    """The tiles to grow cut into batches, one task each: ``per_task`` tiles a batch, or
    (0) one batch per CPU slot, balanced, but no more than :data:`MAX_TILES_PER_TASK` tiles
    a batch; tiles dealt in turn, so neighbouring tiles (similar work) land in different
    batches."""
    if per_task > 0:
        count = -(-len(todo) // per_task)
    else:
        count = max(slots, -(-len(todo) // MAX_TILES_PER_TASK), 1)
    count = min(count, len(todo))
    return [todo[k::count] for k in range(count)]


def grow(args):
    """The run: returns the exit status."""
    clock = Clock(args.timings)
    script = os.path.abspath(args.script)
    if not os.path.isfile(script):
        raise WorldError(f"{args.script}: no such script")
    if args.cpus_per_tile < 1 or args.retries < 0 or args.tiles_per_task < 0:
        raise WorldError(
            "--cpus-per-tile must be at least 1, --retries and --tiles-per-task at least 0"
        )
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
    shared = not args.standalone_tiles
    variants_ok = shared and old is not None and mf.variants_intact(out, old)
    clock.mark("Python started, manifest read")

    # pge lists the tiles and writes the shared variants (on all this machine's cores) while
    # Ray is imported and connects; the tasks get the variants' description through the
    # object store, or read it from DIR on a shared folder.
    created = not os.path.exists(out)
    lister = start_tile_list(program, script, args.seed, overrides)
    writer = None
    if shared and not variants_ok:
        os.makedirs(out, exist_ok=True)
        writer = start_variants(program, script, args, overrides, out)
    ray = None
    progress = Progress(0, 0, args.quiet)
    try:
        if old is None or not old.get("complete") or (shared and not variants_ok):
            # Work is likely: connect now (a complete world is checked first, without Ray).
            ray = connect(args.address)
            clock.mark("Ray imported and connected")
        tiles = tile_list(lister, script)
        clock.mark("pge tiles")
        progress.total = len(tiles)
        done = mf.done_tiles(out, old) if old is not None else {}
        if old is not None and (old.get("variants") is not None) != shared:
            # Tiles of the other form (standalone or referring to shared variants): grown again.
            done = {}
        params = old.get("params") if old is not None else None
        if args.adopt:
            for t in tiles:
                if (t["i"], t["j"]) not in done:
                    entry, tile_params = adopt(out, t, args.seed, overrides, params, shared)
                    if entry is not None:
                        done[(t["i"], t["j"])] = entry
                        params = tile_params
        todo = [t for t in tiles if (t["i"], t["j"]) not in done]
        if todo and ray is None:
            ray = connect(args.address)
            clock.mark("Ray imported and connected")
        # No warm-up task: it starts a worker of its own beside the tiles' (measured: the
        # extra Python processes on each node slowed the tiles more than they saved).
        nodes, local = cluster_nodes(ray) if ray is not None else ([], True)
        variants = old.get("variants") if variants_ok else None
        if writer is not None:
            variants = finish_variants(writer, out, progress)
            clock.mark("variants written")
    except BaseException:
        for proc in (lister, writer):
            if proc is not None and proc.poll() is None:
                proc.kill()
                proc.wait()
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
        clock.mark("manifest written")
        clock.report()
        return 0
    if ray is None:
        ray = connect(args.address)
        nodes, local = cluster_nodes(ray)
    shared_fs = local if args.shared_fs is None else args.shared_fs
    from ray import cloudpickle

    from . import tile as tile_module

    # Ship the task's code with it: workers need Ray and pge, not this package.
    cloudpickle.register_pickle_by_value(tile_module)
    os.makedirs(os.path.join(out, "tiles"), exist_ok=True)
    task = ray.remote(grow_tiles).options(
        num_cpus=args.cpus_per_tile,
        max_retries=args.retries,
        retry_exceptions=False,
        scheduling_strategy="SPREAD",
    )
    variant_cache = args.variant_cache and os.path.abspath(args.variant_cache)
    if args.no_variant_cache or shared:
        variant_cache = None
    description = None
    if shared and not shared_fs:
        with open(os.path.join(out, mf.VARIANTS_JSON), "rb") as f:
            description = ray.put(f.read())
    slots = sum(n // args.cpus_per_tile for _, _, n in nodes)
    pending = {}
    for batch in batches_of(todo, slots, args.tiles_per_task):
        ref = task.remote(
            args.pge, script, args.seed, overrides, [(t["i"], t["j"]) for t in batch],
            args.cpus_per_tile, args.time_limit, variant_cache, shared, description,
            out if shared_fs else None,
        )
        pending[ref] = batch
    clock.mark(f"{len(pending)} tasks of {len(todo)} tiles submitted")
    written = dict(done)
    finished = []
    last_write = time.monotonic()
    try:
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1, timeout=1.0)
            for ref in ready:
                batch = pending.pop(ref)
                result = fetch(ray, ref, batch)
                result["started"] = time.time() - result["seconds"]
                finished.append(result)
                bounds = {(t["i"], t["j"]): t for t in batch}
                for grown in result["tiles"]:
                    t = bounds[(grown["i"], grown["j"])]
                    written[(t["i"], t["j"])] = save_tile(out, t, grown)
                    if params is None:
                        params = params_of(out, t, grown)
                    progress.tile(t["i"], t["j"])
                clock.mark(f"batch of {len(batch)} tiles back from {result['node']}")
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
    clean_scratch(os.path.join(out, "tiles"))
    clock.mark("manifest written")
    total = sum(e["instances"] for e in written.values())
    elapsed = time.monotonic() - progress.start
    progress.say(
        f"world complete: {len(tiles)} tiles, {total} instances in {args.out} ({elapsed:.1f}s)"
    )
    clock.report(finished)
    return 0


def clean_scratch(folder):
    """Removes what a pge killed in the middle of writing a tile left in ``folder`` (its
    temporary ``.tmp*`` files; the tile itself is renamed into place whole or not at all)."""
    for name in os.listdir(folder):
        if name.startswith(".tmp"):
            try:
                os.remove(os.path.join(folder, name))
            except OSError:
                pass


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


def adopt(out, t, seed, overrides, params, shared):
    """The manifest entry and parameters of tile ``t``'s file in ``out`` when it was written
    by ``pge run --tile`` with this seed and these settings, referring to the shared variants
    when ``shared`` (``--variants DIR``) and carrying them otherwise; (None, None) when there
    is no file; an error when it belongs to another run or is of the other form."""
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
        refers = mf.refers_to_variants(data)
    except (WorldError, ValueError) as e:
        raise WorldError(f"{path}: not a tile ({e}); delete it to grow it again") from e
    if refers != shared:
        form = "refers to shared variants" if refers else "carries its variants"
        other = "without" if refers else "with"
        raise WorldError(
            f"{path}: the tile {form}; run pge-world {other} --standalone-tiles, or delete it "
            "to grow it again"
        )
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


def fetch(ray, ref, batch):
    """The result of a batch task, or a one-line error naming the tile (pge's own
    ``tile I,J: FILE:LINE: message``, or the batch's first tile)."""
    from ray.exceptions import RayError, RayTaskError

    first = f"tile {batch[0]['i']},{batch[0]['j']}"
    try:
        return ray.get(ref)
    except RayTaskError as e:
        cause = getattr(e, "cause", None)
        # The task's module travels by value (workers need only Ray and pge), so its
        # exception class is a copy: compare by name.
        if type(cause).__name__ == TileFailed.__name__:
            message = str(cause)
            raise WorldError(message if message.startswith("tile ") else f"{first}: {message}")
        reason = last_line(str(cause if cause is not None else e))
        raise WorldError(f"{first} failed: {reason}") from None
    except RayError as e:
        raise WorldError(
            f"{first} failed after {type(e).__name__}: {last_line(str(e))}"
        ) from None


def save_tile(out, t, grown):
    """The manifest entry of a tile a task grew, its file written (atomically) when the
    task sent its bytes; a task that wrote it itself (a shared folder) sent its hash."""
    name = mf.tile_file(t["i"], t["j"])
    if "glb" in grown:
        mf.write_atomically(os.path.join(out, name), grown["glb"])
    return {
        "i": t["i"],
        "j": t["j"],
        "min": t["min"],
        "max": t["max"],
        "file": name,
        "sha256": grown["sha256"],
        "bytes": grown["bytes"],
        "instances": grown["instances"],
    }


def params_of(out, t, grown):
    """The declared parameters' values, from a tile's ``extras.pge.params``."""
    data = grown.get("glb")
    if data is None:
        with open(os.path.join(out, mf.tile_file(t["i"], t["j"])), "rb") as f:
            data = f.read()
    return mf.glb_root_extras(data).get("params", {})


def main(argv=None):
    """The console script: exit status 0, 1 (a problem to fix) or 2 (usage)."""
    args = parser().parse_args(argv)
    status = run(args)
    if "ray" in sys.modules and argv is None:
        # Connected to a cluster: everything is written (the manifest atomically), and
        # Ray's own shutdown at exit (disconnecting the job, which the cluster notices
        # anyway) takes most of a second. Leave at once.
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(status)
    return status


def run(args):
    """:func:`grow` with its errors as one line on stderr: the exit status."""
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
