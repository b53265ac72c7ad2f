"""The world directory: ``DIR/tiles/I_J.glb`` and the manifest ``DIR/world.json``.

The manifest is always written whole (a temporary file renamed over the old one). While a
world grows it lists the tiles done so far with ``"complete": false``; the last write has
``"complete": true``. A run on the same directory skips every listed tile whose file still
has the recorded SHA-256.
"""

import hashlib
import json
import os
import struct
import tempfile

FORMAT = "pge-world/1"
MANIFEST = "world.json"


class WorldError(Exception):
    """A problem the user fixes: printed as one line, exit status 1."""


def sha256_bytes(data):
    """The SHA-256 of ``data`` as 64 hex digits."""
    return hashlib.sha256(data).hexdigest()


def sha256_file(path):
    """The SHA-256 of the file at ``path``, or None when it cannot be read."""
    try:
        with open(path, "rb") as f:
            return sha256_bytes(f.read())
    except OSError:
        return None


def tile_file(i, j):
    """The file of tile (i, j), relative to the world directory."""
    return f"tiles/{i}_{j}.glb"


def write_atomically(path, data):
    """Writes ``data`` (bytes) to ``path`` through a temporary file renamed over it."""
    folder = os.path.dirname(path) or "."
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=".", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def glb_json(data):
    """The JSON chunk of a .glb."""
    if len(data) < 20 or data[:4] != b"glTF":
        raise WorldError("not a .glb file")
    length, kind = struct.unpack_from("<I4s", data, 12)
    if kind != b"JSON":
        raise WorldError("a .glb without a JSON chunk")
    return json.loads(data[20 : 20 + length])


def glb_root_extras(data):
    """The root ``extras.pge`` of a .glb's JSON chunk (an empty dict when it has none)."""
    return (glb_json(data).get("extras") or {}).get("pge") or {}


def refers_to_variants(data):
    """Whether a tile's .glb refers to the world's shared variants (a buffer whose URI is
    ``../variants.bin``) rather than carrying them."""
    buffers = glb_json(data).get("buffers") or []
    return any(b.get("uri") == "../" + VARIANTS_BIN for b in buffers)


def identity(script_sha256, seed, overrides):
    """What makes two runs the same world: the script's hash, the seed, the --set values."""
    return {"scriptSha256": script_sha256, "seed": seed, "set": dict(overrides)}


def read(directory):
    """The manifest in ``directory``, or None when there is none."""
    path = os.path.join(directory, MANIFEST)
    if not os.path.exists(path):
        return None
    try:
        with open(path, encoding="utf-8") as f:
            manifest = json.load(f)
    except (OSError, ValueError) as e:
        raise WorldError(f"{path}: not a world manifest ({e}); choose another --out") from e
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        raise WorldError(f"{path}: not a {FORMAT} manifest; choose another --out")
    return manifest


def same_world(manifest, ident):
    """Whether ``manifest`` was written for the world ``ident`` (see :func:`identity`)."""
    return all(manifest.get(k) == v for k, v in ident.items())


def done_tiles(directory, manifest):
    """The tiles of ``manifest`` whose file in ``directory`` still has the recorded hash,
    keyed by (i, j)."""
    done = {}
    for t in manifest.get("tiles", []):
        path = os.path.join(directory, t["file"])
        if sha256_file(path) == t["sha256"]:
            done[(t["i"], t["j"])] = t
    return done


VARIANTS_BIN = "variants.bin"
VARIANTS_JSON = "variants.json"


def variants_entry(directory):
    """The manifest's record of the shared variants in ``directory`` (written by ``pge run
    --variants-out``): each file's name, SHA-256 and length; None when either is missing."""
    entry = {}
    for key, name in (("", VARIANTS_BIN), ("description", VARIANTS_JSON)):
        try:
            with open(os.path.join(directory, name), "rb") as f:
                data = f.read()
        except OSError:
            return None
        entry[key or "file"] = name
        entry[(key + "Sha256") if key else "sha256"] = sha256_bytes(data)
        entry[(key + "Bytes") if key else "bytes"] = len(data)
    return entry


def variants_intact(directory, manifest):
    """Whether the shared variants ``manifest`` records are in ``directory`` unchanged."""
    recorded = manifest.get("variants")
    return recorded is not None and variants_entry(directory) == recorded


def write(directory, ident, script, params, tiles, complete, variants=None):
    """Writes the manifest atomically: ``tiles`` in (i, j) order, their instance total, and
    the shared variants' record (:func:`variants_entry`) when the tiles refer to them."""
    tiles = sorted(tiles, key=lambda t: (t["i"], t["j"]))
    manifest = {"format": FORMAT, "script": script}
    manifest.update(ident)
    manifest["params"] = params
    if variants is not None:
        manifest["variants"] = variants
    manifest["complete"] = complete
    manifest["instances"] = sum(t["instances"] for t in tiles)
    manifest["tiles"] = tiles
    text = json.dumps(manifest, indent=1) + "\n"
    write_atomically(os.path.join(directory, MANIFEST), text.encode("utf-8"))
