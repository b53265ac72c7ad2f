"""Stand-ins for the unit tests: a .glb built from a JSON document, and a fake ``pge``."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

# A `pge` that does to the file system what pge-world asks of it: `pge tiles` prints two
# tiles; `pge run --variants-out D` writes the variants; `pge run --tile ... --out-dir D`
# writes one file a tile (its bytes name the tile, the seed and, with `--variants D`, hold
# D/variants.json; none with `--set quiet=1`). `pge world init SCRIPT --out D` creates
# D/tiles and prints a new world's state, or the JSON in $FAKE_WORLD_INIT; `pge world
# variants D` prints the record of D's variants (changed when $FAKE_WORLD_CHANGED is set);
# `adopt` prints [[1, 0]]; `finish` 42 instances; `add` prints nothing.
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
if args[0] == "world":
    what = args[1]
    if what == "init":
        os.makedirs(os.path.join(after("--out"), "tiles"), exist_ok=True)
        default = (
            '{"created": true, "fresh": true, "complete": false, "variants": false, "tiles": []}'
        )
        print(os.environ.get("FAKE_WORLD_INIT", default))
    elif what == "variants":
        record = {"file": "variants.bin", "sha256": "0" * 64, "bytes": 1,
                  "description": "variants.json", "descriptionSha256": "1" * 64,
                  "descriptionBytes": 1}
        print(json.dumps({"changed": bool(os.environ.get("FAKE_WORLD_CHANGED")),
                          "variants": record}))
    elif what == "adopt":
        print("[[1, 0]]")
    elif what == "finish":
        print('{"tiles": 2, "instances": 42}')
    sys.exit(0)
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
    if "quiet=1" not in sets:
        with open(os.path.join(after("--out-dir"), f"{i}_{j}.glb"), "w") as f:
            f.write(f"tile {i},{j} seed {after('--seed')} {description}")
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
