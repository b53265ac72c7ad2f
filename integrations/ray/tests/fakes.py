"""Stand-ins for the unit tests: a .glb built from a JSON document, and a fake ``pge``."""

from __future__ import annotations

import json
import os
import struct
import sys
from pathlib import Path
from typing import Any

# A `pge` that does to the file system what pge-world asks of it: `pge tiles` prints two
# tiles; `pge run --variants-out D` writes the variants; `pge run --tile ... --out-dir D
# --stats` writes one file a tile (its bytes name the tile, the seed and, with `--variants
# D`, hold D/variants.json) and prints one --stats line a tile (none with `--set quiet=1`).
# It records its arguments in $FAKE_PGE_LOG; `--set fail=MESSAGE` fails like pge, its
# error the last line on stderr.
FAKE_PGE = """\
import json, os, sys
args = sys.argv[1:]
with open(os.environ["FAKE_PGE_LOG"], "a") as log:
    log.write(json.dumps(args) + "\\n")
def after(flag):
    return args[args.index(flag) + 1] if flag in args else None
sets = [args[k + 1] for k, a in enumerate(args) if a == "--set"]
for s in sets:
    if s.startswith("fail="):
        sys.stderr.write("warming up\\n" + s[5:] + "\\n\\n")
        sys.exit(1)
if args[0] == "tiles":
    print(json.dumps([{"i": i, "j": 0, "min": [i, 0], "max": [i + 1, 1]} for i in range(2)]))
    sys.exit(0)
if after("--variants-out"):
    for name in ("variants.bin", "variants.json"):
        with open(os.path.join(after("--variants-out"), name), "w") as f:
            f.write(name + " of seed " + after("--seed"))
    sys.exit(0)
description = ""
if after("--variants"):
    with open(os.path.join(after("--variants"), "variants.json")) as f:
        description = f.read()
tiles = [args[k + 1] for k, a in enumerate(args) if a == "--tile"]
for t in tiles:
    i, j = (int(x) for x in t.split(","))
    with open(os.path.join(after("--out-dir"), f"{i}_{j}.glb"), "w") as f:
        f.write(f"tile {i},{j} seed {after('--seed')} {description}")
    if "quiet=1" not in sets:
        print(json.dumps({"tile": [i, j], "instances": 10 * i + j}))
"""


def fake_pge(folder: Path) -> Path:
    """Write the fake ``pge`` into ``folder``: its path."""
    path = folder / "fake-pge"
    path.write_text(f"#!{sys.executable}\n{FAKE_PGE}")
    os.chmod(path, 0o755)
    return path


def calls(log: Path) -> list[list[str]]:
    """Return the argument lists the fake ``pge`` was called with."""
    return [json.loads(line) for line in log.read_text().splitlines()]


def glb(document: dict[str, Any]) -> bytes:
    """Return a .glb whose JSON chunk is ``document`` (no binary chunk)."""
    text = json.dumps(document).encode()
    text += b" " * (-len(text) % 4)
    header = struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(text))
    return header + struct.pack("<I4s", len(text), b"JSON") + text


def tile_glb(
    i: int,
    j: int,
    seed: int = 1,
    params: dict[str, Any] | None = None,
    instances: int = 7,
    shared: bool = True,
) -> bytes:
    """Return a tile as ``pge run --tile I,J`` writes it, as far as pge-world reads one."""
    document: dict[str, Any] = {
        "asset": {"version": "2.0"},
        "extras": {
            "pge": {
                "seed": seed,
                "params": params if params is not None else {"spin": 0, "broken": False},
                "forest": {"tileIndex": [i, j], "instances": instances},
            }
        },
    }
    if shared:
        document["buffers"] = [{"uri": "../variants.bin", "byteLength": 4}]
    return glb(document)
