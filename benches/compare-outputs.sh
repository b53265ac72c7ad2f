#!/usr/bin/env bash
# Byte-for-byte comparison of what two builds of `pge` write, for refactors and
# optimisations that must not change any output:
#
#   benches/compare-outputs.sh BASE_PGE NEW_PGE [WORK_DIR]
#
# Runs both binaries on every library script (species, forests, L-systems, modellers,
# examples) with default parameters, the new one at --threads 1 and 2; plus growth stages,
# an .obj, a tile of the mixed and big forests, and a world's shared variants with a tile
# that refers to them. Prints one line per file that differs and a summary; exits 1 when any
# output differs or a run fails. Run from the repository root; copy both binaries out of
# target/ first if you time them as well.
set -euo pipefail
cd "$(dirname "$0")/.."
if [[ $# -lt 2 ]]; then
    sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
fi
base=$(realpath "$1")
new=$(realpath "$2")
work=${3:-$(mktemp -d)}
mkdir -p "$work/base" "$work/new"
same=0
differ=0

# run NAME ARGS...: both binaries write NAME (the new one at 1 and 2 threads).
run() {
    local name=$1
    shift
    "$base" "$@" -q -o "$work/base/$name"
    for threads in 1 2; do
        local out="$work/new/t$threads/$name"
        mkdir -p "$work/new/t$threads"
        "$new" "$@" -q --threads "$threads" -o "$out"
        if cmp -s "$work/base/$name" "$out"; then
            same=$((same + 1))
        else
            differ=$((differ + 1))
            echo "differs: $name (--threads $threads): pge $*"
        fi
    done
}

while IFS= read -r script; do
    name="$(basename "$(dirname "$script")")_$(basename "$script" .lua)"
    case "$name" in
    forests_big) run "$name.tile.glb" run "$script" --tile 1,1 ;;
    *) run "$name.glb" run "$script" ;;
    esac
done < <(find scripts -name '*.lua' -not -path '*/lib/*' -not -path '*/data/*' | sort)
run stages.glb run scripts/species/broadleaf.lua --stages 10,40,70
run oak.obj run scripts/species/oak.lua
run mixed_tile.glb run scripts/forests/mixed.lua --tile 1,1

# Shared variants: the world's variants, then a tile that refers to them.
for who in base new; do
    bin=$base
    [[ $who == new ]] && bin=$new
    rm -rf "$work/$who/world"
    mkdir -p "$work/$who/world/tiles"
    "$bin" run scripts/forests/mixed.lua --variants-out "$work/$who/world" -q
    "$bin" run scripts/forests/mixed.lua --tile 0,1 --variants "$work/$who/world" -q \
        -o "$work/$who/world/tiles/0_1.glb"
done
for f in variants.bin variants.json tiles/0_1.glb; do
    if cmp -s "$work/base/world/$f" "$work/new/world/$f"; then
        same=$((same + 1))
    else
        differ=$((differ + 1))
        echo "differs: shared variants, $f"
    fi
done

echo "compare-outputs: $same same, $differ differ (files in $work)"
[[ $differ -eq 0 ]]
