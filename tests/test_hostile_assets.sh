#!/bin/sh
# test_hostile_assets.sh: malformed assets end as exit status 1 with a message naming the file and the
# reason, never as a crash, an abort or a hang of `cbvh cook`: PLY face indices past the vertex count,
# PLY files cut inside the header or the faces (plain and .gz), an import that hangs (a FIFO nobody writes)
# or dies of a signal in its child process; in a batch, the broken asset fails and the others cook.
#
# Environment: as tests/test_tool.sh (CBVH_TOOL). Every cook runs under timeout(1) when it exists, so a
# hang fails the test instead of stopping `make check`.

name=test_hostile_assets.sh
. "$(dirname "$0")/tool_test_lib.sh"

limit=
command -v timeout >/dev/null 2>&1 && limit="timeout 120"

# refused STATUS NAME FILE PATTERN [OPTIONS...]: cooks FILE, expects STATUS and PATTERN on stderr (with FILE's name).
refused() {
    expect=$1 label=$2 file=$3 pattern=$4
    shift 4
    if run "$expect" "$label" $limit "$CBVH" cook --quiet "$@" "$file" "$tmp/o.cbvh"; then
        check "... the message names the file and says '$pattern'" \
            sh -c "grep -F '$file' '$tmp/err' | grep -q '$pattern'"
    fi
    check "... no output" test ! -e "$tmp/o.cbvh"
}

# A triangle and a face whose last index is $1, in an ASCII PLY.
ply_index() {
    printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n'
    printf 'element face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n'
    printf '3 0 1 %s\n' "$1"
}
for index in 2147483647 4294967295 5; do
    ply_index "$index" >"$tmp/index$index.ply"
    refused 1 "PLY face index $index of 3 vertices" "$tmp/index$index.ply" "out of range"
done
# The same in a binary PLY, index 1000000 (0x000f4240 little-endian).
{
    printf 'ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n'
    printf 'property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n'
    printf '\0\0\0\0\0\0\0\0\0\0\0\0\0\0\200\77\0\0\0\0\0\0\0\0\0\0\0\0\0\0\200\77\0\0\0\0'
    printf '\3\0\0\0\0\1\0\0\0\100\102\17\0'
} >"$tmp/binary-index.ply"
refused 1 "binary PLY face index 1000000 of 3 vertices" "$tmp/binary-index.ply" "out of range"

models=$(assimp_models)
if [ -n "$models" ] && [ -f "$models/PLY/cube_binary.ply" ] && [ -f "$models/PLY/Wuson.ply" ]; then
    head -c 100 "$models/PLY/cube_binary.ply" >"$tmp/cut-header.ply"
    refused 1 "a binary PLY cut inside its header (assimp's reader loops)" "$tmp/cut-header.ply" \
        "past the end of"
    gzip -c "$tmp/cut-header.ply" >"$tmp/cut-header.ply.gz"
    refused 1 "... the same as .ply.gz" "$tmp/cut-header.ply.gz" "past the end of"
    head -c 500000 "$models/PLY/Wuson.ply" >"$tmp/cut-faces.ply"
    refused 1 "an ASCII PLY cut inside its faces (assimp's triangulation asserts)" "$tmp/cut-faces.ply" \
        "no vertex indices"
    gzip -c "$tmp/cut-faces.ply" >"$tmp/cut-faces.ply.gz"
    refused 1 "... the same as .ply.gz" "$tmp/cut-faces.ply.gz" "no vertex indices"

    mkdir "$tmp/batch"
    run 1 "a batch: the cut PLY fails, the whole one cooks" $limit "$CBVH" cook --jobs 2 --output-dir "$tmp/batch" \
        "$tmp/cut-header.ply" "$models/PLY/Wuson.ply"
    check "... one JSON line per asset" test "$(wc -l <"$tmp/out")" -eq 2
    check "... the cut one's line is an error" grep -q '"input": *"[^"]*cut-header.ply".*"error"' "$tmp/out"
    check "... Wuson cooked" test -s "$tmp/batch/Wuson.cbvh"
    check "... nothing for the cut one" test ! -e "$tmp/batch/cut-header.cbvh"
else
    skip "truncated PLYs: assimp-testmodels not installed"
fi

# An import that never ends: a FIFO no one writes to (the import's open blocks).
if mkfifo "$tmp/never.ply" 2>/dev/null; then
    refused 1 "an import that hangs, --import-timeout 1" "$tmp/never.ply" "longer than 1 s" --import-timeout 1
    # An import that dies of a signal (as assimp does on some files): the child gets it while it hangs.
    children_of() {
        parent=$1
        for st in /proc/[0-9]*/stat; do
            fields=$(cat "$st" 2>/dev/null) || continue
            # shellcheck disable=SC2086
            set -- $fields
            [ "${4:-}" = "$parent" ] && echo "$1"
        done
    }
    for sig in SEGV ABRT; do
        [ -d /proc/self ] || { skip "SIG$sig in the import: no /proc"; continue; }
        "$CBVH" cook --quiet --import-timeout 60 "$tmp/never.ply" "$tmp/o.cbvh" >"$tmp/out" 2>"$tmp/err" &
        cook=$!
        child=
        tries=0
        while [ -z "$child" ] && [ "$tries" -lt 400 ]; do
            child=$(children_of $cook | head -1)
            tries=$((tries + 1))
            [ -n "$child" ] || sleep 0.05
        done
        if [ -z "$child" ]; then
            fail "SIG$sig in the import: no import process found"
            kill $cook 2>/dev/null
            wait $cook
            continue
        fi
        kill -s "$sig" "$child"
        wait $cook
        status=$?
        check "SIG$sig in the import: exit status 1 (was $status)" test "$status" -eq 1
        what=crashed
        [ "$sig" = ABRT ] && what=aborted
        check "... the message names the file and says assimp $what" \
            sh -c "grep -F '$tmp/never.ply' '$tmp/err' | grep -q 'assimp $what'"
        check "... no output" test ! -e "$tmp/o.cbvh"
    done
else
    skip "import timeout: mkfifo failed"
fi

run 2 "--import-timeout takes a number of seconds" "$CBVH" cook --import-timeout soon gen:cube "$tmp/o.cbvh"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' >"$tmp/triangle.obj"
run 0 "--import-timeout 0: no limit" "$CBVH" cook --quiet --import-timeout 0 "$tmp/triangle.obj" "$tmp/o.cbvh"
finish
