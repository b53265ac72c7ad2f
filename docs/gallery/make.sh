#!/usr/bin/env bash
# Remakes the gallery: a close view (2 m from the trunk, eye at 1.6 m) and a far view (the
# whole model framed) of every species, with `pge preview --screenshot` under Xvfb
# (.ci/preview-deps installs it). Run from the repository root after `cargo build`.
set -euo pipefail
pge=${PGE:-target/debug/pge}
shot() {
    local out=$1
    shift
    xvfb-run -a -s "-screen 0 1280x1024x24" "$pge" preview "$@" --screenshot "$out.png"
}
for script in scripts/species/*.lua; do
    name=$(basename "$script" .lua)
    shot "docs/gallery/$name-close" "$script" --camera 2,1.6,0,1.2,0
    shot "docs/gallery/$name-far" "$script"
done
