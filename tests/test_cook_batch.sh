#!/bin/sh
# test_cook_batch.sh: batch cooking: `cbvh cook --output-dir DIR IN...`, `--manifest FILE`, `--jobs N`: one
# JSON line per asset, success or error; exit status 0 only when every asset cooked; outputs
# byte-identical to single cooks; refusals before anything is cooked.
#
# Environment: as tests/test_tool.sh (CBVH_TOOL).

name=test_cook_batch.sh
. "$(dirname "$0")/tool_test_lib.sh"

# Five small assets: four tetrahedra of different sizes and one file with no triangles.
mkdir "$tmp/assets" "$tmp/single" "$tmp/batch" "$tmp/manifest"
for k in 1 2 3 4; do
    printf 'v 0 0 0\nv %s 0 0\nv 0 %s 0\nv 0 0 %s\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n' "$k" "$k.5" "$k.25" \
        >"$tmp/assets/tet$k.obj"
    "$CBVH" cook --quiet "$tmp/assets/tet$k.obj" "$tmp/single/tet$k.cbvh" >/dev/null
done
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\n' >"$tmp/assets/lines.obj"

run 0 "a batch of four assets, two jobs" "$CBVH" cook --jobs 2 --output-dir "$tmp/batch" "$tmp/assets/tet1.obj" \
    "$tmp/assets/tet2.obj" "$tmp/assets/tet3.obj" "$tmp/assets/tet4.obj"
check "... one line per asset" test "$(wc -l <"$tmp/out")" -eq 4
same=0
for k in 1 2 3 4; do cmp -s "$tmp/single/tet$k.cbvh" "$tmp/batch/tet$k.cbvh" && same=$((same + 1)); done
check "... outputs byte-identical to single cooks" test "$same" -eq 4
if [ "$has_python" = 1 ]; then
    check "... each line is a JSON object naming its input and output" python3 - "$tmp/out" "$tmp" <<'PY'
import json, sys
lines = open(sys.argv[1]).read().splitlines()
seen = set()
for line in lines:
    d = json.loads(line)
    assert d["output"] == d["input"].replace("/assets/", "/batch/").replace(".obj", ".cbvh"), d
    assert d["triangles"]["kept"] == 4 and "error" not in d, d
    seen.add(d["input"])
assert len(seen) == 4, seen
PY
fi

run 1 "a batch with an asset that fails" "$CBVH" cook --jobs 2 --output-dir "$tmp/batch" "$tmp/assets/tet1.obj" \
    "$tmp/assets/lines.obj" "$tmp/assets/tet2.obj"
check "... still one line per asset" test "$(wc -l <"$tmp/out")" -eq 3
check "... the failure's message names its file on stderr" grep -q "lines.obj: no triangles" "$tmp/err"
if [ "$has_python" = 1 ]; then
    check "... the failure's line holds the error" python3 - "$tmp/out" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1]).read().splitlines()]
bad = [r for r in rows if "error" in r]
assert len(bad) == 1 and bad[0]["input"].endswith("lines.obj") and bad[0]["error"]["status"] == 1, rows
PY
fi
check "... the failed asset wrote no output" test ! -e "$tmp/batch/lines.cbvh"

# A manifest: comments, blank lines, IN<TAB>OUT and IN into --output-dir.
{
    printf '# assets\n\n'
    printf '%s\t%s\n' "$tmp/assets/tet1.obj" "$tmp/manifest/first.cbvh"
    printf '%s\n' "$tmp/assets/tet2.obj"
} >"$tmp/list.txt"
run 0 "a manifest" "$CBVH" cook --manifest "$tmp/list.txt" --output-dir "$tmp/manifest"
check "... IN<TAB>OUT and IN lines cook where they say" \
    sh -c "cmp -s '$tmp/single/tet1.cbvh' '$tmp/manifest/first.cbvh' && cmp -s '$tmp/single/tet2.cbvh' '$tmp/manifest/tet2.cbvh'"
run 0 "a manifest on standard input" sh -c "'$CBVH' cook --manifest - --output-dir '$tmp/manifest' <'$tmp/list.txt'"

# Pipeline options: --select, --scale, --up-axis, --depfile.
cat >"$tmp/scene.obj" <<'OBJ'
mtllib scene.mtl
o Visual
v 0 0 0
v 1 0 0
v 0 1 0
v 0 0 1
usemtl red
f 1 2 3
f 1 2 4
o UCX_box
v 5 5 5
v 6 5 5
v 5 6 5
f 5 6 7
OBJ
printf 'newmtl red\nKd 1 0 0\n' >"$tmp/scene.mtl"
run 0 "--select 'UCX_*' keeps the collision node only" "$CBVH" cook --select 'UCX_*' "$tmp/scene.obj" "$tmp/ucx.cbvh" &&
    check "... one triangle" grep -q " 1 triangles" "$tmp/out"
run 1 "--select matching no node" "$CBVH" cook --select 'nothing*' "$tmp/scene.obj" "$tmp/none.cbvh" &&
    check "... says so" grep -q "no triangles in the nodes that --select 'nothing\*' matches" "$tmp/err"
run 0 "--scale 2 --up-axis z" "$CBVH" cook --scale 2 --up-axis z "$tmp/scene.obj" "$tmp/zup.cbvh"
run 0 "... info" "$CBVH" info "$tmp/zup.cbvh" &&
    check "... bounds doubled and turned: +Y up becomes +Z up" grep -q "^bounds: \[0 -10 0\] - \[12 -0 12\]" "$tmp/out"
run 0 "--depfile" "$CBVH" cook --depfile "$tmp/scene.d" "$tmp/scene.obj" "$tmp/my scene.cbvh" &&
    check "... names the output (escaped), the asset and its .mtl" \
        grep -qF "$(printf '%s' "$tmp/my scene.cbvh" | sed 's/ /\\ /g'): $tmp/scene.obj $tmp/scene.mtl" "$tmp/scene.d"
run 2 "--depfile with a batch" "$CBVH" cook --depfile "$tmp/x.d" --output-dir "$tmp/batch" "$tmp/scene.obj"
run 2 "--scale 0" "$CBVH" cook --scale 0 "$tmp/scene.obj" "$tmp/x.cbvh"
run 2 "--up-axis w" "$CBVH" cook --up-axis w "$tmp/scene.obj" "$tmp/x.cbvh"

# Refusals, before anything is cooked.
printf '%s\n' "$tmp/assets/tet3.obj" >"$tmp/nodir.txt"
run 2 "a manifest line without an output and no --output-dir" "$CBVH" cook --manifest "$tmp/nodir.txt" &&
    check "... names the manifest and the line" grep -q "nodir.txt: line 1" "$tmp/err"
run 2 "a missing manifest" "$CBVH" cook --manifest "$tmp/missing.txt" --output-dir "$tmp/batch"
run 2 "--output-dir that is not a folder" "$CBVH" cook --output-dir "$tmp/assets/tet1.obj" "$tmp/assets/tet2.obj"
mkdir "$tmp/other"
cp "$tmp/assets/tet1.obj" "$tmp/other/tet1.obj"
run 2 "two assets into one output" "$CBVH" cook --output-dir "$tmp/batch" "$tmp/assets/tet1.obj" "$tmp/other/tet1.obj" &&
    check "... names both inputs" grep -q "both" "$tmp/err"
run 2 "--jobs 0" "$CBVH" cook --jobs 0 --output-dir "$tmp/batch" "$tmp/assets/tet1.obj"
run 2 "a generated scene in a batch" "$CBVH" cook --output-dir "$tmp/batch" gen:cube
run 2 "a batch with no input" "$CBVH" cook --output-dir "$tmp/batch"

finish
