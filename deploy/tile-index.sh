#!/bin/sh
# Prints "I,J" of the K-th tile (from 0) of a forest script, in the order `pge tiles` lists
# them: the index of a Kubernetes Indexed Job or a Slurm array task picks the tile.
# Usage: tile-index.sh SCRIPT K [pge tiles options...]
set -eu
script=$1
k=$2
shift 2
tile=$(pge tiles "$script" "$@" | grep -o '"i":[0-9]*,"j":[0-9]*' | sed -n "$((k + 1))p")
if [ -z "$tile" ]; then
  echo "tile-index.sh: $script has no tile number $k (see: pge tiles $script)" >&2
  exit 1
fi
echo "$tile" | sed 's/"i":\([0-9]*\),"j":\([0-9]*\)/\1,\2/'
