#!/usr/bin/env bash
# Remakes the gallery as three.js draws it (GLTFLoader, its own mipmaps, headless Chromium):
# every species from 2 m (the eye at 1.6 m, looking at the trunk at 1.2 m, a low sun across
# the bark) and whole, and the mixed forest from the air and at eye level
# (tests/clients/views.mjs). Installs Chromium, three and playwright-core on first use
# (.ci/browser-deps). Run from the repository root; uses target/release/pge (or $PGE),
# building it when missing.
set -euo pipefail
cd "$(dirname "$0")/../.."
pge=${PGE:-target/release/pge}
[[ -x "$pge" ]] || cargo build --release --bin pge
bash .ci/browser-deps
glb=$(mktemp -d)
trap 'rm -rf "$glb"' EXIT
for script in scripts/species/*.lua; do
    "$pge" run "$script" -q -o "$glb/$(basename "$script" .lua).glb"
done
"$pge" run scripts/forests/mixed.lua -q -o "$glb/forest.glb"
rm -f docs/gallery/*.png docs/gallery/*.jpg
species=()
for f in "$glb"/*.glb; do
    [[ "$f" == "$glb/forest.glb" ]] || species+=("$f")
done
node tests/clients/views.mjs gallery target/clients/node/node_modules docs/gallery \
    "${species[@]}" --forest "$glb/forest.glb"
