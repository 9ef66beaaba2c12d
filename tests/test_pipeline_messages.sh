#!/bin/sh
# test_pipeline_messages.sh: what a build pipeline reads from the cbvh command: --quiet says nothing on
# success; a read-only OUT is refused unless --force; coordinate errors name the file's axis and kind; -j N
# is --jobs N; usage errors name options with two dashes; JSON numbers in plain notation; hints for
# --jobs on one cook and for a bare --compress level; blank raycast lines; report --sample 0 refused; a full
# disk's message names no XXXXXX template; info's section table aligned; manifest paths from the current
# folder; output names of 255 bytes; --json on every command and failure; the exact range's refusal and flush.
#
# Environment: as tests/test_tool.sh (CBVH_TOOL).

name=test_pipeline_messages.sh
. "$(dirname "$0")/tool_test_lib.sh"

printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' >"$tmp/tri.obj"

# Item 15: --quiet prints nothing on success.
run 0 "cook --quiet" "$CBVH" cook --quiet "$tmp/tri.obj" "$tmp/tri.cbvh"
check "... prints nothing on stdout" test ! -s "$tmp/out"
check "... nor on stderr" test ! -s "$tmp/err"

# Item 12: a read-only OUT is refused unless --force.
cp "$tmp/tri.cbvh" "$tmp/before.cbvh"
chmod a-w "$tmp/tri.cbvh"
run 2 "cook over a read-only OUT" "$CBVH" cook --quiet --layout binary "$tmp/tri.obj" "$tmp/tri.cbvh"
check "... says it is read-only and what --force does" grep -q "read-only.*--force" "$tmp/err"
check "... leaves it unchanged" cmp -s "$tmp/tri.cbvh" "$tmp/before.cbvh"
run 0 "... --force replaces it" "$CBVH" cook --quiet --force --layout binary "$tmp/tri.obj" "$tmp/tri.cbvh"
check "... with the new content" sh -c "! cmp -s '$tmp/tri.cbvh' '$tmp/before.cbvh'"
chmod u+w "$tmp/tri.cbvh"

# Item 14: a NaN or infinite z is named as such, whatever --up-axis does to the axes.
printf 'v 0 0 0\nv 1 0 0\nv 2 3 nan\nf 1 2 3\n' >"$tmp/nan.obj"
printf 'v 0 0 0\nv 1 0 0\nv 2 3 1e39\nf 1 2 3\n' >"$tmp/inf.obj"
for axis in y z; do
    run 1 "a NaN z, --up-axis $axis" "$CBVH" cook --quiet --up-axis $axis "$tmp/nan.obj" "$tmp/o.cbvh"
    check "... 'z coordinate is NaN'" grep -q "z coordinate is NaN" "$tmp/err"
    run 1 "an infinite z (1e39), --up-axis $axis" "$CBVH" cook --quiet --up-axis $axis "$tmp/inf.obj" "$tmp/o.cbvh"
    check "... 'z coordinate is infinite'" grep -q "z coordinate is infinite" "$tmp/err"
done
check "... and says what the vertex number counts" grep -q "as assimp numbers them" "$tmp/err"

# The exact range (docs/EXACTNESS.md): a coordinate past 2^40 is refused naming the limit; one below 2^-40
# is stored as 0 and counted.
printf 'v 0 0 0\nv 1 0 0\nv 2 3 2e12\nf 1 2 3\n' >"$tmp/far.obj"
run 1 "a coordinate of 2e12" "$CBVH" cook --quiet "$tmp/far.obj" "$tmp/o.cbvh"
check "... 'beyond the exact range of +-2^40'" grep -q "z coordinate 2e+12 is beyond the exact range of +-2^40" "$tmp/err"
printf 'v 0 0 0\nv 1 0 1e-20\nv 0 1 0\nf 1 2 3\n' >"$tmp/tiny.obj"
run 0 "a coordinate of 1e-20" "$CBVH" cook --json "$tmp/tiny.obj" "$tmp/o.cbvh"
check "... counted as flushed" grep -q '"flushed_coordinates": 1' "$tmp/out"
run 0 "... and in the summary" "$CBVH" cook "$tmp/tiny.obj" "$tmp/o.cbvh"
check "... '1 coordinates below 2^-40 stored as 0'" grep -q "1 coordinates below 2^-40 stored as 0" "$tmp/out"

# Item 18: -j N and -jN mean --jobs N.
mkdir "$tmp/batch"
run 0 "cook -j 2" "$CBVH" cook -j 2 --output-dir "$tmp/batch" "$tmp/tri.obj"
check "... cooks" test -s "$tmp/batch/tri.cbvh"
run 0 "cook -j2" "$CBVH" cook -j2 --output-dir "$tmp/batch" "$tmp/tri.obj"
run 2 "cook -j (no value)" "$CBVH" cook --output-dir "$tmp/batch" "$tmp/tri.obj" -j
run 0 "--jobs on a single cook" "$CBVH" cook --jobs 2 "$tmp/tri.obj" "$tmp/o.cbvh"
check "... warns that it does nothing there" grep -q "warning: --jobs" "$tmp/err"
run 2 "--compress 9 IN OUT" "$CBVH" cook --compress 9 "$tmp/tri.obj" "$tmp/o.cbvh"
check "... points to --compress=9" grep -q -- "--compress=9" "$tmp/err"
run 2 "bench --rays x" "$CBVH" bench --rays x gen:cube
check "... names --rays with two dashes" sh -c "grep -q -- '--rays' '$tmp/err' && ! grep -q -- '---' '$tmp/err'"
run 2 "report --seed x" "$CBVH" report --gen cube --seed x
check "... names --seed with two dashes" sh -c "grep -q -- '--seed' '$tmp/err' && ! grep -q -- '---' '$tmp/err'"
run 0 "cook --json of a 12-triangle cube" "$CBVH" cook --json gen:cube "$tmp/cube.cbvh"
check "... bytes_per_triangle in plain notation" sh -c \
    "grep -q '\"bytes_per_triangle\": [0-9.]*,\$' '$tmp/out' && ! grep -q 'e+' '$tmp/out'"

# A blank line in raycast input is skipped.
printf '0.2 0.2 5 0 0 -1\n\n   \n0.2 0.2 5 0 0 -1\n' >"$tmp/rays.txt"
"$CBVH" raycast "$tmp/tri.cbvh" <"$tmp/rays.txt" >"$tmp/hits" 2>"$tmp/err"
check "raycast skips blank lines (exit 0)" test $? -eq 0
check "... two results" test "$(wc -l <"$tmp/hits")" -eq 2

# Item 17: report --sample 0 would claim exactness on no rays.
run 2 "report --sample 0" "$CBVH" report --gen cube --sample 0

# A write that fails (file size limit, as a full disk) names no XXXXXX template.
if (trap '' XFSZ; ulimit -f 1) 2>/dev/null; then
    (
        trap '' XFSZ
        ulimit -f 1
        "$CBVH" cook --quiet gen:sphere:2000 "$tmp/big.cbvh"
    ) >"$tmp/out" 2>"$tmp/err"
    check "a write past the size limit fails (exit 2)" test $? -eq 2
    check "... with a message naming no template" sh -c "grep -q big.cbvh '$tmp/err' && ! grep -q XXXXXX '$tmp/err'"
    check "... and no output" test ! -e "$tmp/big.cbvh"
else
    skip "write failure: ulimit -f unavailable"
fi

# info's section table: every row's columns line up with the header's.
printf 'mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n' >"$tmp/named.obj"
printf 'newmtl red\nKd 1 0 0\n' >"$tmp/m.mtl"
"$CBVH" cook --quiet "$tmp/named.obj" "$tmp/named.cbvh"
"$CBVH" info "$tmp/named.cbvh" >"$tmp/info"
check "info lists a material-names section" grep -q "^  material-names " "$tmp/info"
check "... its table columns line up (crc32 column at one place)" awk '
    /^sections:/ { on = 1; next }
    on && /^$/ { exit }
    on && /type/ { col = index($0, "crc32"); next }
    on { n++; if (substr($0, col - 1, 1) != " " || substr($0, col, 1) == " ") bad = 1 }
    END { exit (n >= 3 && !bad) ? 0 : 1 }' "$tmp/info"

# Item 11: output names up to 255 bytes cook (the temporary name fits too); a message about a long path keeps
# its reason (the path comes last and is what gets cut).
long=$(printf '%0250d' 0)
run 0 "an output name of 255 bytes" "$CBVH" cook --quiet "$tmp/tri.obj" "$tmp/$long.cbvh"
check "... is written" test -s "$tmp/$long.cbvh"
run 2 "an output of 255 bytes in a missing folder" "$CBVH" cook --quiet "$tmp/tri.obj" "$tmp/missing/$long.cbvh"
check "... the message keeps its reason" grep -q "No such file or directory" "$tmp/err"

# Item 16: --json on every command, failures included.
if [ "$has_python" = 1 ]; then
    # json_error STATUS NAME CMD...: the command exits STATUS and prints one JSON object with error.status.
    json_error() {
        expect=$1 label=$2
        shift 2
        run "$expect" "$label" "$@" &&
            check "... prints a JSON error with status $expect" python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
assert d['error']['status'] == $expect and d['error']['message'], d" "$tmp/out"
    }
    json_error 2 "cook --json, usage error" "$CBVH" cook --json --bogus
    json_error 2 "cook --json, a missing input" "$CBVH" cook --json "$tmp/none.obj" "$tmp/o.cbvh"
    json_error 2 "info --json, a missing file" "$CBVH" info --json "$tmp/none.cbvh"
    json_error 2 "verify --json, a missing file" "$CBVH" verify --json "$tmp/none.cbvh"
    json_error 2 "raycast --json, usage error" "$CBVH" raycast --json
    json_error 2 "demo --json, usage error" "$CBVH" demo --json extra
    run 0 "verify --json" "$CBVH" verify --json "$tmp/tri.cbvh" &&
        check "... {file, ok: true}" python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
assert d['ok'] is True and d['file'].endswith('tri.cbvh'), d" "$tmp/out"
    printf '0.2 0.2 5 0 0 -1\n5 5 5 0 0 1\n' >"$tmp/rays2.txt"
    "$CBVH" raycast --json "$tmp/tri.cbvh" <"$tmp/rays2.txt" >"$tmp/out" 2>"$tmp/err"
    check "raycast --json: a JSON object per ray, a hit and a miss" python3 -c "
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
assert rows[0]['hit'] is True and rows[0]['triangle'] == 0 and abs(rows[0]['t'] - 5) < 1e-6, rows
assert rows[1] == {'hit': False}, rows" "$tmp/out"
else
    skip "--json: no python3"
fi

# On a terminal the import shows how much of the asset it has read, as the later phases show theirs
# (script(1) gives the cook a terminal).
if command -v script >/dev/null 2>&1 &&
    script -qec "'$CBVH' cook '$tmp/tri.obj' '$tmp/tty.cbvh'" "$tmp/typescript" >/dev/null 2>&1; then
    check "the import shows a percentage on a terminal" sh -c "tr '\\r' '\\n' <'$tmp/typescript' | grep -a -q 'import *[0-9][0-9]*%'"
else
    skip "import progress: no util-linux script(1)"
fi

# Manifest paths are relative to the current folder, not to the manifest's.
mkdir "$tmp/lists" "$tmp/out-m"
printf 'tri.obj\tout-m/tri.cbvh\n' >"$tmp/lists/manifest.txt"
(cd "$tmp" && "$CBVH" cook --manifest lists/manifest.txt) >"$tmp/out" 2>"$tmp/err"
check "manifest paths resolve from the current folder" test -s "$tmp/out-m/tri.cbvh"
finish
