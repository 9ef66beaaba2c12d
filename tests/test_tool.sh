#!/bin/sh
# test_tool.sh: end-to-end tests of the cbvh command: help, exit codes, cooking generated and real meshes, info, verify, raycast against brute force, atomic output.
#
# Environment (set by `make check` through AM_TESTS_ENVIRONMENT):
#   CBVH_TOOL        the built tools/cbvh
#   CBVH_TOP_SRCDIR  the source tree (read only; the tests generate their own inputs and do not need it)
#   CBVH_ASSIMP_MODELS  optional: folder of Debian's assimp-testmodels (found with dpkg -L otherwise)
# Writes only into a mktemp folder, removed at exit.

name=test_tool.sh
. "$(dirname "$0")/tool_test_lib.sh"

# ---- help, version, usage errors ----------------------------------------------------------

run 0 "cbvh --help" "$CBVH" --help && check "cbvh --help lists the commands" grep -q "raycast" "$tmp/out"
run 0 "cbvh --version" "$CBVH" --version &&
    check "--version names the library and format versions" grep -q "library .*file format [0-9]" "$tmp/out"
commands=$("$CBVH" --help | awk '/^Commands:/ { on = 1; next } on && NF == 0 { on = 0 } on { print $1 }')
check "cbvh --help lists at least five commands" test "$(echo "$commands" | wc -w)" -ge 5
for c in $commands; do
    run 0 "cbvh $c --help" "$CBVH" "$c" --help &&
        check "cbvh $c --help prints its usage" grep -q "^Usage: cbvh $c" "$tmp/out"
    run 0 "cbvh $c --version" "$CBVH" "$c" --version
    run 0 "cbvh help $c" "$CBVH" help "$c"
done

run 2 "no command" "$CBVH"
run 2 "unknown command" "$CBVH" frobnicate
run 2 "cook without arguments" "$CBVH" cook
run 2 "cook with three paths" "$CBVH" cook gen:cube a b
run 2 "cook --leaf-size 0" "$CBVH" cook --leaf-size 0 gen:cube "$tmp/x.cbvh"
run 2 "cook --leaf-size 17" "$CBVH" cook --leaf-size 17 gen:cube "$tmp/x.cbvh"
run 2 "cook --bins x" "$CBVH" cook --bins x gen:cube "$tmp/x.cbvh"
run 2 "cook --layout wide8" "$CBVH" cook --layout wide8 gen:cube "$tmp/x.cbvh"
run 2 "cook --compress=10" "$CBVH" cook --compress=10 gen:cube "$tmp/x.cbvh"
run 2 "cook --unknown" "$CBVH" cook --unknown gen:cube "$tmp/x.cbvh"
run 2 "cook --json=1 (no value allowed)" "$CBVH" cook --json=1 gen:cube "$tmp/x.cbvh"
run 2 "cook of an unknown generated scene" "$CBVH" cook gen:pyramid "$tmp/x.cbvh"
run 2 "cook of a missing input" "$CBVH" cook "$tmp/missing.obj" "$tmp/x.cbvh" &&
    check "the message names the missing input" grep -q "missing.obj" "$tmp/err"
check "failed cooks wrote nothing" test ! -e "$tmp/x.cbvh"
run 2 "info without a file" "$CBVH" info
run 2 "verify with two files" "$CBVH" verify a b
run 2 "raycast --traversal bogus" "$CBVH" raycast --traversal bogus "$tmp/x.cbvh"
run 2 "raycast --traversal without value" "$CBVH" raycast "$tmp/x.cbvh" --traversal
run 2 "demo with an argument" "$CBVH" demo extra

# ---- cooking generated scenes, options, determinism ----------------------------------------

for spec in cube sphere:2000 terrain:5000 soup:3000 demo; do
    f="$tmp/gen-$(echo "$spec" | tr : -).cbvh"
    run 0 "cook gen:$spec" "$CBVH" cook --quiet "gen:$spec" "$f" &&
        run 0 "verify gen:$spec" "$CBVH" verify "$f" && check "verify prints ok" grep -qx ok "$tmp/out"
done
run 0 "cook gen:cube summary" "$CBVH" cook gen:cube "$tmp/cube.cbvh" &&
    check "the summary counts 12 triangles" grep -q "12 triangles" "$tmp/out"

for opts in "--compress" "--compress=9" "--quantize-vertices" "--no-remap" "--no-materials" "--leaf-size 1" \
    "--leaf-size 16 --bins 4" "--traversal-cost 2 --intersection-cost 0.5" "--layout wide4" \
    "--layout wide4 --leaf-size 1 --compress" "--layout binary"; do
    # shellcheck disable=SC2086
    run 0 "cook gen:demo $opts" "$CBVH" cook --quiet $opts gen:demo "$tmp/opt.cbvh" &&
        run 0 "verify gen:demo $opts" "$CBVH" verify "$tmp/opt.cbvh"
done
"$CBVH" cook --quiet gen:sphere:20000 "$tmp/raw.cbvh" >/dev/null
"$CBVH" cook --quiet --compress=9 gen:sphere:20000 "$tmp/z.cbvh" >/dev/null
check "--compress makes the file smaller" test "$(wc -c <"$tmp/z.cbvh")" -lt "$(wc -c <"$tmp/raw.cbvh")"

"$CBVH" cook --quiet gen:terrain:20000 "$tmp/det1.cbvh" >/dev/null
"$CBVH" cook --quiet gen:terrain:20000 "$tmp/det2.cbvh" >/dev/null
check "cooking is deterministic (gen:terrain)" cmp -s "$tmp/det1.cbvh" "$tmp/det2.cbvh"
"$CBVH" cook --quiet --layout wide4 gen:terrain:20000 "$tmp/det3.cbvh" >/dev/null
"$CBVH" cook --quiet --layout wide4 gen:terrain:20000 "$tmp/det4.cbvh" >/dev/null
check "cooking is deterministic (gen:terrain, wide4)" cmp -s "$tmp/det3.cbvh" "$tmp/det4.cbvh"
run 0 "info of a wide4 file" "$CBVH" info "$tmp/det3.cbvh" && check "info names the wide4 layout" grep -q "^layout: wide4" "$tmp/out"
run 0 "info of a default file" "$CBVH" info "$tmp/det1.cbvh" && check "info names the default, wide4 layout" grep -q "^layout: wide4" "$tmp/out"
"$CBVH" cook --quiet --layout binary gen:terrain:20000 "$tmp/det5.cbvh" >/dev/null
run 0 "info of a binary file" "$CBVH" info "$tmp/det5.cbvh" && check "info names the binary layout" grep -q "^layout: binary" "$tmp/out"

# ---- cook --json, info, info --json ------------------------------------------------------

run 0 "cook --json" "$CBVH" cook --json gen:sphere:2000 "$tmp/sphere.cbvh" && cp "$tmp/out" "$tmp/cook.json"
run 0 "info" "$CBVH" info "$tmp/sphere.cbvh" &&
    check "info shows the sections" grep -q "^  nodes " "$tmp/out"
check "info shows a leaf histogram" grep -q "^leaf sizes:" "$tmp/out"
check "info shows the box inflation" grep -q "box inflation" "$tmp/out"
run 0 "info --json" "$CBVH" info --json "$tmp/sphere.cbvh" && cp "$tmp/out" "$tmp/info.json"
if [ "$has_python" = 1 ]; then
    check "cook --json is valid JSON" json_valid "$tmp/cook.json"
    check "info --json is valid JSON" json_valid "$tmp/info.json"
    check "info --json and cook --json agree on triangles and nodes" python3 - "$tmp/cook.json" "$tmp/info.json" <<'EOF'
import json, sys
cook = json.load(open(sys.argv[1]))
info = json.load(open(sys.argv[2]))
assert cook["triangles"]["kept"] == info["triangles"], (cook["triangles"], info["triangles"])
assert cook["tree"]["nodes"] == info["tree"]["nodes"]
assert cook["tree"]["depth"] == info["tree"]["depth"]
assert cook["file_size"] == info["file_size"]
assert sum(info["tree"]["leaf_histogram"].values()) == info["tree"]["leaves"]
assert info["box_inflation"]["max"] >= info["box_inflation"]["mean"] >= 0
assert abs(cook["tree"]["sah_cost"] - info["tree"]["sah_cost"]) <= 1e-3 * info["tree"]["sah_cost"]
# boxes on a frame per node contain the exact ones, and 8-bit steps (255 divides 65535) are coarser
# than 16-bit ones within the same frames: exact <= 16 bits <= 8 bits; 16 bits within 0.1% of exact
tree = info["tree"]
exact, f16, f8 = tree["sah_cost_exact"], tree["sah_cost_frame16"], tree["sah_cost_frame8"]
assert exact * (1 - 1e-12) <= f16 <= f8 and f16 <= 1.001 * exact and f8 > f16, tree
# the worst box is named by its node (a wide4 node carries its children's boxes: and a child slot)
assert info["layout"] == "wide4" and info["box_inflation"]["max_node"] < info["tree"]["nodes"], info
assert 0 <= info["box_inflation"]["max_slot"] < 4, info
EOF
    "$CBVH" cook --quiet gen:cube "$tmp/we\"ird\\name.cbvh" >/dev/null &&
        "$CBVH" info --json "$tmp/we\"ird\\name.cbvh" >"$tmp/weird.json"
    check "info --json escapes quotes and backslashes in the file name" json_valid "$tmp/weird.json"
else
    skip "JSON validation: python3 not found"
fi

# ---- verify: good, corrupt, unreadable ------------------------------------------------------

good="$tmp/sphere.cbvh"
size=$(wc -c <"$good")
cp "$good" "$tmp/flipped.cbvh"
# Flip one byte in the middle of the first section (past the header and table).
printf '\377' | dd of="$tmp/flipped.cbvh" bs=1 seek=$((size / 2)) conv=notrunc 2>/dev/null
if cmp -s "$good" "$tmp/flipped.cbvh"; then
    printf '\000' | dd of="$tmp/flipped.cbvh" bs=1 seek=$((size / 2)) conv=notrunc 2>/dev/null
fi
run 1 "verify a corrupt file" "$CBVH" verify "$tmp/flipped.cbvh" &&
    check "the message names the corrupt file" grep -q "flipped.cbvh: " "$tmp/err"
head -c $((size - 1)) "$good" >"$tmp/truncated.cbvh"
run 1 "verify a truncated file" "$CBVH" verify "$tmp/truncated.cbvh" &&
    check "the message names the truncated file" grep -q "truncated.cbvh: " "$tmp/err"
: >"$tmp/empty.cbvh"
run 1 "verify an empty file" "$CBVH" verify "$tmp/empty.cbvh"
echo "not a cbvh file" >"$tmp/text.cbvh"
run 1 "verify a text file" "$CBVH" verify "$tmp/text.cbvh"
run 1 "info of a corrupt file" "$CBVH" info "$tmp/flipped.cbvh"
run 1 "raycast on a corrupt file" "$CBVH" raycast "$tmp/flipped.cbvh"
run 2 "verify a missing file" "$CBVH" verify "$tmp/nothing-here.cbvh" &&
    check "the message names the missing file" grep -q "nothing-here.cbvh" "$tmp/err"
run 2 "verify a folder" "$CBVH" verify "$tmp"

# ---- atomic output ---------------------------------------------------------------------------

run 2 "cook into a folder that does not exist" "$CBVH" cook gen:cube "$tmp/no/such/dir/x.cbvh"
check "... and nothing was created" test ! -e "$tmp/no"
mkdir "$tmp/atomic"
echo "garbage" >"$tmp/bad.obj"
run 1 "cook of a file that is not a mesh" "$CBVH" cook "$tmp/bad.obj" "$tmp/atomic/x.cbvh" &&
    check "the message names the bad input" grep -q "bad.obj: " "$tmp/err"
check "... and left nothing in the output folder" test -z "$(ls -A "$tmp/atomic")"
cp "$good" "$tmp/atomic/keep.cbvh"
run 1 "cook of a bad input over an existing file" "$CBVH" cook "$tmp/bad.obj" "$tmp/atomic/keep.cbvh"
check "... left the existing file unchanged" cmp -s "$good" "$tmp/atomic/keep.cbvh"
check "... and no temporary file" test "$(ls -A "$tmp/atomic")" = "keep.cbvh"
if [ "$(id -u)" != 0 ]; then
    chmod a-w "$tmp/atomic"
    run 2 "cook into a read-only folder over an existing file" "$CBVH" cook gen:sphere:500 "$tmp/atomic/keep.cbvh"
    chmod u+w "$tmp/atomic"
    check "... left the existing file unchanged" cmp -s "$good" "$tmp/atomic/keep.cbvh"
else
    skip "read-only output folder: running as root, permissions are not enforced"
fi
run 0 "cook over an existing file" "$CBVH" cook --quiet gen:cube "$tmp/atomic/keep.cbvh" &&
    run 0 "... which is replaced by a valid file" "$CBVH" verify "$tmp/atomic/keep.cbvh"

# ---- raycast: traversals agree, brute force agrees, input errors --------------------------

# A small triangle soup written as OBJ (one object, triangles only), so the original triangle
# ids are the face order; rays aimed at triangle interiors plus random rays.
awk 'BEGIN {
    srand(12345); n = 300
    for (i = 0; i < n; i++) {
        cx = rand() * 10; cy = rand() * 10; cz = rand() * 10
        for (k = 0; k < 3; k++)
            printf "v %.6f %.6f %.6f\n", cx + rand() * 2 - 1, cy + rand() * 2 - 1, cz + rand() * 2 - 1
    }
    for (i = 0; i < n; i++) printf "f %d %d %d\n", 3 * i + 1, 3 * i + 2, 3 * i + 3
}' >"$tmp/soup.obj"
awk 'BEGIN { srand(777) }
    /^v / { nv++; x[nv] = $2; y[nv] = $3; z[nv] = $4 }
    END {
        for (r = 0; r < 400; r++) {
            ox = rand() * 30 - 10; oy = rand() * 30 - 10; oz = rand() * 30 - 10
            if (r % 2 == 0) {
                t = int(rand() * nv / 3); a = 3 * t + 1
                wb = 0.1 + rand() * 0.4; wc = 0.1 + rand() * 0.4; wa = 1 - wb - wc
                tx = wa * x[a] + wb * x[a + 1] + wc * x[a + 2]
                ty = wa * y[a] + wb * y[a + 1] + wc * y[a + 2]
                tz = wa * z[a] + wb * z[a + 1] + wc * z[a + 2]
                printf "%.6f %.6f %.6f %.6f %.6f %.6f\n", ox, oy, oz, tx - ox, ty - oy, tz - oz
            } else {
                printf "%.6f %.6f %.6f %.6f %.6f %.6f 0.5 %.3f\n", ox, oy, oz, rand() - 0.5, rand() - 0.5, rand() - 0.5, rand() * 40
            }
        }
    }' "$tmp/soup.obj" >"$tmp/rays.txt"
# Brute force in awk (double precision Moller-Trumbore over every triangle): "tri t margin" or "-1".
awk 'NR == FNR { if ($1 == "v") { nv++; x[nv] = $2; y[nv] = $3; z[nv] = $4 } next }
    {
        ox = $1; oy = $2; oz = $3; dx = $4; dy = $5; dz = $6
        tmin = NF == 8 ? $7 : 0; tmax = NF == 8 ? $8 : 1e300
        best = tmax; bt = -1; bm = 1
        for (t = 0; t < nv / 3; t++) {
            a = 3 * t + 1
            e1x = x[a + 1] - x[a]; e1y = y[a + 1] - y[a]; e1z = z[a + 1] - z[a]
            e2x = x[a + 2] - x[a]; e2y = y[a + 2] - y[a]; e2z = z[a + 2] - z[a]
            px = dy * e2z - dz * e2y; py = dz * e2x - dx * e2z; pz = dx * e2y - dy * e2x
            det = e1x * px + e1y * py + e1z * pz
            if (det == 0) continue
            sx = ox - x[a]; sy = oy - y[a]; sz = oz - z[a]
            u = (sx * px + sy * py + sz * pz) / det
            qx = sy * e1z - sz * e1y; qy = sz * e1x - sx * e1z; qz = sx * e1y - sy * e1x
            v = (dx * qx + dy * qy + dz * qz) / det
            tt = (e2x * qx + e2y * qy + e2z * qz) / det
            if (u < 0 || v < 0 || u + v > 1 || tt < tmin || tt > best) continue
            best = tt; bt = t; m = u < v ? u : v; if (1 - u - v < m) m = 1 - u - v; bm = m
        }
        if (bt < 0) print -1; else printf "%d %.9g %.9g\n", bt, best, bm
    }' "$tmp/soup.obj" "$tmp/rays.txt" >"$tmp/brute.txt"

run 0 "cook the soup OBJ" "$CBVH" cook --quiet "$tmp/soup.obj" "$tmp/soup.cbvh"
"$CBVH" raycast "$tmp/soup.cbvh" <"$tmp/rays.txt" >"$tmp/hits-sorted.txt"
check "raycast prints one line per ray" test "$(wc -l <"$tmp/hits-sorted.txt")" -eq "$(wc -l <"$tmp/rays.txt")"
check "some rays hit and some miss" sh -c "grep -q '^-1\$' '$tmp/hits-sorted.txt' && grep -qv '^-1\$' '$tmp/hits-sorted.txt'"
check "sorted raycast agrees with the brute force" awk '
    NR == FNR { bt[FNR] = $1; bd[FNR] = $2; bm[FNR] = $3; n = FNR; next }
    {
        graze = (bm[FNR] != "" && bm[FNR] < 1e-4)
        if ($1 == -1 && bt[FNR] == -1) next
        if ($1 == bt[FNR]) { d = $2 - bd[FNR]; if (d < 0) d = -d; if (d <= 1e-4 * (1 + bd[FNR])) next }
        if (graze) next
        printf "ray %d: cbvh \"%s\", brute force \"%s %s\"\n", FNR, $0, bt[FNR], bd[FNR] > "/dev/stderr"; bad++
    }
    END { exit bad > 0 }' "$tmp/brute.txt" "$tmp/hits-sorted.txt"
for tr in stackless unsorted distance stream; do
    "$CBVH" raycast --traversal "$tr" "$tmp/soup.cbvh" <"$tmp/rays.txt" >"$tmp/hits-$tr.txt"
    check "raycast --traversal $tr gives the same answers as sorted" cmp -s "$tmp/hits-sorted.txt" "$tmp/hits-$tr.txt"
done
run 0 "cook the soup OBJ with --layout wide4" "$CBVH" cook --quiet --layout wide4 "$tmp/soup.obj" "$tmp/soup-w4.cbvh"
for tr in sorted stackless unsorted distance stream; do
    "$CBVH" raycast --traversal "$tr" "$tmp/soup-w4.cbvh" <"$tmp/rays.txt" >"$tmp/hits-w4-$tr.txt"
    check "wide4 raycast --traversal $tr gives the binary layout's answers" cmp -s "$tmp/hits-sorted.txt" "$tmp/hits-w4-$tr.txt"
done
awk '{ print ($1 == -1) ? 0 : 1 }' "$tmp/hits-sorted.txt" >"$tmp/expect-any.txt"
for tr in sorted stackless stream; do
    "$CBVH" raycast --any --traversal "$tr" "$tmp/soup.cbvh" <"$tmp/rays.txt" >"$tmp/any-$tr.txt"
    check "raycast --any --traversal $tr agrees with closest hit" cmp -s "$tmp/expect-any.txt" "$tmp/any-$tr.txt"
done
"$CBVH" cook --quiet --no-remap "$tmp/soup.obj" "$tmp/soup-noremap.cbvh" >/dev/null
"$CBVH" raycast "$tmp/soup-noremap.cbvh" <"$tmp/rays.txt" | awk '{ print ($1 == -1) ? -1 : $2 }' >"$tmp/t-noremap.txt"
awk '{ print ($1 == -1) ? -1 : $2 }' "$tmp/hits-sorted.txt" >"$tmp/t-remap.txt"
check "--no-remap changes ids, not distances" cmp -s "$tmp/t-remap.txt" "$tmp/t-noremap.txt"

if [ "$has_python" = 1 ]; then
    python3 - "$tmp/rays.txt" "$tmp/rays.bin" <<'EOF'
import struct, sys
out = open(sys.argv[2], "wb")
for line in open(sys.argv[1]):
    f = [float(x) for x in line.split()]
    tmin, tmax = (f[6], f[7]) if len(f) == 8 else (0.0, float("inf"))
    out.write(struct.pack("<8f", f[0], f[1], f[2], tmin, f[3], f[4], f[5], tmax))
EOF
    "$CBVH" raycast --binary "$tmp/soup.cbvh" <"$tmp/rays.bin" >"$tmp/hits.bin"
    check "raycast --binary gives the same answers as text" python3 - "$tmp/hits.bin" "$tmp/hits-sorted.txt" <<'EOF'
import struct, sys
data = open(sys.argv[1], "rb").read()
lines = open(sys.argv[2]).read().split("\n")[:-1]
assert len(data) == 16 * len(lines), (len(data), len(lines))
for i, line in enumerate(lines):
    tri, t, u, v = struct.unpack_from("<I3f", data, 16 * i)
    if line == "-1":
        assert tri == 0xFFFFFFFF, (i, tri)
    else:
        f = line.split()
        assert tri == int(f[0]) and "%.9g" % t == f[1] and "%.9g" % u == f[2] and "%.9g" % v == f[3], (i, line)
EOF
    "$CBVH" raycast --binary --any "$tmp/soup.cbvh" <"$tmp/rays.bin" | od -An -v -tu1 | tr -s ' ' '\n' | sed '/^$/d' >"$tmp/any-bin.txt"
    check "raycast --binary --any gives one byte per ray, as text" cmp -s "$tmp/expect-any.txt" "$tmp/any-bin.txt"
    head -c 40 "$tmp/rays.bin" >"$tmp/partial.bin"
    run 1 "raycast --binary with a partial record" sh -c "'$CBVH' raycast --binary '$tmp/soup.cbvh' <'$tmp/partial.bin'" &&
        check "... reports the trailing bytes" grep -q "8 trailing bytes" "$tmp/err"
else
    skip "binary raycast: python3 not found"
fi

printf '0 0 0 1 0 0\n1 2 3\n' >"$tmp/bad-rays.txt"
run 1 "raycast with a short line" sh -c "'$CBVH' raycast '$tmp/soup.cbvh' <'$tmp/bad-rays.txt'" &&
    check "... names line 2" grep -q "line 2: " "$tmp/err"
check "... after answering line 1" test "$(wc -l <"$tmp/out")" -eq 1
printf '0 0 0 1 0 0\n0 0 0 1 0 0\n0 0 0 1 0 zero\n' >"$tmp/bad-rays.txt"
run 1 "raycast with a field that is not a number" sh -c "'$CBVH' raycast '$tmp/soup.cbvh' <'$tmp/bad-rays.txt'" &&
    check "... names line 3 and the field" grep -q "line 3: .*zero" "$tmp/err"
printf '0 0 0 1 0 0 0 1 2\n' >"$tmp/bad-rays.txt"
run 1 "raycast with 9 fields" sh -c "'$CBVH' raycast '$tmp/soup.cbvh' <'$tmp/bad-rays.txt'" &&
    check "... names line 1" grep -q "line 1: " "$tmp/err"
printf '0 0 0 1 0 0 0 1x\n' >"$tmp/bad-rays.txt"
run 1 "raycast with trailing garbage in a number" sh -c "'$CBVH' raycast '$tmp/soup.cbvh' <'$tmp/bad-rays.txt'"
printf 'nan 0 0 1 0 0\n0 0 0 0 0 0\n0 0 0 1 0 0 5 1\n' >"$tmp/odd-rays.txt"
run 0 "raycast of invalid rays (NaN, zero direction, tmin > tmax)" sh -c "'$CBVH' raycast '$tmp/soup.cbvh' <'$tmp/odd-rays.txt'" &&
    check "... answers a miss for each" test "$(grep -c '^-1$' "$tmp/out")" -eq 3

# ---- real meshes, one per assimp format family ----------------------------------------------

models=$(assimp_models)
if [ -n "$models" ] && [ -d "$models" ]; then
    for m in OBJ/spider.obj PLY/Wuson.ply PLY/cube_binary.ply STL/Spider_binary.stl STL/Spider_ascii.stl \
        glTF2/BoxTextured-glTF/BoxTextured.gltf glTF2/BoxTextured-glTF-Binary/BoxTextured.glb \
        FBX/spider.fbx Collada/duck.dae Collada/teapot_instancenodes.DAE 3DS/fels.3ds IFC/AC14-FZK-Haus.ifc; do
        if [ ! -f "$models/$m" ]; then
            skip "cook $m: not in $models"
            continue
        fi
        out="$tmp/model.cbvh"
        run 0 "cook $m" "$CBVH" cook --quiet "$models/$m" "$out" && run 0 "verify $m" "$CBVH" verify "$out"
    done
    # The spider exists as binary and ASCII STL: the same mesh whichever way it was stored.
    if [ -f "$models/STL/Spider_binary.stl" ] && [ -f "$models/STL/Spider_ascii.stl" ]; then
        # (the ASCII file's decimals differ from the binary floats in the last bit, so compare the
        # triangle counts and the tree's shape rather than the bytes)
        "$CBVH" cook --quiet "$models/STL/Spider_binary.stl" "$tmp/sb.cbvh" >/dev/null
        "$CBVH" cook --quiet "$models/STL/Spider_ascii.stl" "$tmp/sa.cbvh" >/dev/null
        "$CBVH" info "$tmp/sb.cbvh" | grep -E "^(triangles|tree):" >"$tmp/sb.txt"
        "$CBVH" info "$tmp/sa.cbvh" | grep -E "^(triangles|tree):" >"$tmp/sa.txt"
        check "binary and ASCII STL of the spider give the same triangles and tree shape" \
            sh -c "test -s '$tmp/sb.txt' && cmp -s '$tmp/sb.txt' '$tmp/sa.txt'"
    fi
    if [ -f "$models/PLY/cube.ply" ]; then
        run 0 "cook PLY/cube.ply" "$CBVH" cook "$models/PLY/cube.ply" "$tmp/c.cbvh" &&
            check "the PLY cube has 12 triangles" grep -q "12 triangles" "$tmp/out"
        "$CBVH" cook --quiet "$models/PLY/cube.ply" "$tmp/c1.cbvh" >/dev/null
        check "cooking a real mesh is deterministic" cmp -s "$tmp/c.cbvh" "$tmp/c1.cbvh"
        if command -v gzip >/dev/null 2>&1; then
            gzip -c "$models/PLY/cube.ply" >"$tmp/cube.ply.gz"
            run 0 "cook a .ply.gz" "$CBVH" cook --quiet "$tmp/cube.ply.gz" "$tmp/cgz.cbvh"
            check "... to the same bytes as the plain .ply" cmp -s "$tmp/c.cbvh" "$tmp/cgz.cbvh"
        fi
    fi
    if [ -f "$models/PLY/points.ply" ]; then
        run 1 "cook of a point cloud (no triangles)" "$CBVH" cook "$models/PLY/points.ply" "$tmp/p.cbvh" &&
            check "... says there are no triangles" grep -q "no triangles" "$tmp/err"
    fi
else
    skip "real meshes: the Debian package assimp-testmodels is not installed"
fi

# ---- downloadable meshes (npm packages, fetched by tools/quickstart.sh test) -------------

if [ -n "${CBVH_BUNNY:-}" ] && [ -s "$CBVH_BUNNY" ]; then
    run 0 "cook the npm bunny (OBJ)" "$CBVH" cook --json "$CBVH_BUNNY" "$tmp/bunny.cbvh" &&
        check "... keeps its 3674 triangles" grep -qE '"kept": 3674,' "$tmp/out"
    run 0 "verify the bunny" "$CBVH" verify "$tmp/bunny.cbvh"
else
    skip "npm bunny: CBVH_BUNNY is not set (sh tools/quickstart.sh test fetches it)"
fi
if [ -n "${CBVH_DRAGON_MESH:-}" ] && [ -s "$CBVH_DRAGON_MESH" ]; then
    run 0 "cook the 871K-triangle dragon (PLY)" "$CBVH" cook --json "$CBVH_DRAGON_MESH" "$tmp/dragon.cbvh" &&
        check "... keeps 871K triangles" grep -qE '"kept": 871[0-9]{3},' "$tmp/out"
    run 0 "verify the dragon" "$CBVH" verify "$tmp/dragon.cbvh"
    printf '%s\n' "-0.01 0.12 1  0 0 -1" "0 0.1 -1  0 0 1" "5 5 5  1 1 1" >"$tmp/dragon-rays.txt"
    "$CBVH" raycast "$tmp/dragon.cbvh" <"$tmp/dragon-rays.txt" >"$tmp/dr-sorted.txt"
    "$CBVH" raycast --traversal stream "$tmp/dragon.cbvh" <"$tmp/dragon-rays.txt" >"$tmp/dr-stream.txt"
    check "dragon: sorted and stream raycasts agree" cmp -s "$tmp/dr-sorted.txt" "$tmp/dr-stream.txt"
    check "dragon: a ray from outside away from it misses" sh -c "tail -n 1 '$tmp/dr-sorted.txt' | grep -qx -- -1"
    rm -f "$tmp/dragon.cbvh"
else
    skip "npm dragon: CBVH_DRAGON_MESH is not set (sh tools/quickstart.sh test fetches it)"
fi

# ---- demo ----------------------------------------------------------------------------------

run 0 "demo (every query kind, checked against brute force)" env TMPDIR="$tmp" "$CBVH" demo &&
    check "demo ends with ok" grep -q "^cbvh demo: ok" "$tmp/out"
check "demo removed its temporary file" test -z "$(ls -d "$tmp"/cbvh-demo-* 2>/dev/null)"

finish
