#!/bin/sh
# test_cook_safety.sh: `cbvh cook` never destroys data: the input as output, devices, FIFOs, folders and
# symbolic links as outputs, file modes, interruption by signals, --json on failure, and assets whose
# scene graph importers leave holes in (issue 12's defects 1-5 and 7, each a regression test).
#
# Environment: as tests/test_tool.sh (CBVH_TOOL, CBVH_ASSIMP_MODELS).

name=test_cook_safety.sh
. "$(dirname "$0")/tool_test_lib.sh"

# ---- the input as output (defect 2) -----------------------------------------------------------

cat >"$tmp/tri.obj" <<'OBJ'
v 0 0 0
v 1 0 0
v 0 1 0
v 0 0 1
f 1 2 3
f 1 2 4
OBJ
cp "$tmp/tri.obj" "$tmp/tri.orig"
run 2 "cook IN IN is refused" "$CBVH" cook "$tmp/tri.obj" "$tmp/tri.obj" &&
    check "... the message names the output and says why" grep -q "tri.obj: is the input file itself" "$tmp/err"
ln "$tmp/tri.obj" "$tmp/hard.obj"
run 2 "cook IN to a hard link of IN is refused" "$CBVH" cook "$tmp/tri.obj" "$tmp/hard.obj"
ln -s "$tmp/tri.obj" "$tmp/soft.obj"
run 2 "cook IN to a symbolic link to IN is refused" "$CBVH" cook "$tmp/tri.obj" "$tmp/soft.obj"
run 2 "cook a symbolic link to IN onto IN is refused" "$CBVH" cook "$tmp/soft.obj" "$tmp/tri.obj"
check "the asset is intact after all four" cmp -s "$tmp/tri.obj" "$tmp/tri.orig"

# ---- outputs that are not regular files (defect 3) ---------------------------------------------

mkfifo "$tmp/fifo" 2>/dev/null && {
    run 2 "cook to a FIFO is refused" "$CBVH" cook "$tmp/tri.obj" "$tmp/fifo" &&
        check "... the message says it is a FIFO" grep -q "is a FIFO" "$tmp/err"
    check "... the FIFO is still a FIFO" test -p "$tmp/fifo"
}
mkdir "$tmp/folder"
run 2 "cook to a folder is refused" "$CBVH" cook "$tmp/tri.obj" "$tmp/folder" &&
    check "... the message says it is a folder" grep -q "is a folder" "$tmp/err"
check "... the folder is still a folder" test -d "$tmp/folder"
if [ -c /dev/null ]; then
    # /dev/null, not /dev/full: replacing it would be visible to the whole machine if the refusal broke.
    run 2 "cook to a character device is refused" "$CBVH" cook "$tmp/tri.obj" /dev/null &&
        check "... the message says it is a character device" grep -q "is a character device" "$tmp/err"
    check "... /dev/null is still a character device" test -c /dev/null
fi
printf 'keep me' >"$tmp/target.txt"
ln -s "$tmp/target.txt" "$tmp/link.cbvh"
run 0 "cook to a symbolic link replaces the link" "$CBVH" cook "$tmp/tri.obj" "$tmp/link.cbvh"
check "... the link is now a regular cooked file" sh -c "test -f '$tmp/link.cbvh' && test ! -L '$tmp/link.cbvh'"
check "... the file it pointed to is untouched" sh -c "test \"\$(cat '$tmp/target.txt')\" = 'keep me'"
run 0 "... and it verifies" "$CBVH" verify "$tmp/link.cbvh"

# ---- modes (defect 5) -------------------------------------------------------------------------

mode_of() { stat -c %a "$1" 2>/dev/null || stat -f %Lp "$1"; }
(umask 077 && "$CBVH" cook --quiet "$tmp/tri.obj" "$tmp/private.cbvh" >/dev/null)
check "a new file honours umask 077 (mode 600)" test "$(mode_of "$tmp/private.cbvh")" = 600
(umask 022 && "$CBVH" cook --quiet "$tmp/tri.obj" "$tmp/public.cbvh" >/dev/null)
check "a new file honours umask 022 (mode 644)" test "$(mode_of "$tmp/public.cbvh")" = 644
chmod 640 "$tmp/public.cbvh"
(umask 000 && "$CBVH" cook --quiet "$tmp/tri.obj" "$tmp/public.cbvh" >/dev/null)
check "a replaced file keeps its mode (640)" test "$(mode_of "$tmp/public.cbvh")" = 640

# ---- interruption (defect 4) ------------------------------------------------------------------

# A cook killed at moments spread over its run, the write phase included: no temporary file stays.
mkdir "$tmp/killed"
for moment in 0.3:TERM 0.6:INT 0.9:HUP 1.2:TERM 1.5:INT 1.8:HUP 2.1:TERM 2.4:INT; do
    "$CBVH" cook --quiet gen:sphere:1500000 "$tmp/killed/big.cbvh" >/dev/null 2>&1 &
    pid=$!
    sleep "${moment%:*}"
    kill -s "${moment#*:}" "$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
done
left=$(ls -A "$tmp/killed" | grep -v '^big\.cbvh$' | wc -l)
check "cooks killed by SIGTERM, SIGINT and SIGHUP at 8 moments left no temporary file" test "$left" -eq 0
if [ -e "$tmp/killed/big.cbvh" ]; then
    run 0 "... and any big.cbvh that exists is complete" "$CBVH" verify "$tmp/killed/big.cbvh"
fi

# ---- --json on failure (defect 7) -------------------------------------------------------------

printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\n' >"$tmp/empty.obj"
run 1 "cook --json of a file with lines only" "$CBVH" cook --json "$tmp/empty.obj" "$tmp/e.cbvh"
if [ "$has_python" = 1 ]; then
    check "... prints one JSON object with the error" python3 - "$tmp/out" "$tmp/empty.obj" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
assert d["input"] == sys.argv[2] and d["error"]["status"] == 1, d
assert "no triangles" in d["error"]["message"] and d["error"]["file"] == sys.argv[2], d
PY
    run 2 "cook --json to a folder" "$CBVH" cook --json "$tmp/tri.obj" "$tmp/folder"
    check "... prints the error as JSON, exit status 2" python3 -c "
import json, sys; d = json.load(open(sys.argv[1])); assert d['error']['status'] == 2 and 'folder' in d['error']['message'], d" "$tmp/out"
fi

# ---- scene graphs with holes (defect 1) and hostile sizes (defect 8) ----------------------------

models=$(assimp_models)
if [ -n "$models" ] && [ -f "$models/RAW/WithColor.raw" ]; then
    # RAW/WithColor.raw: two groups of two triangles; assimp's root node counts a child it never fills.
    run 0 "cook RAW/WithColor.raw (a NULL child in the node graph)" "$CBVH" cook --json "$models/RAW/WithColor.raw" "$tmp/wc.cbvh"
    check "... keeps all four triangles of both groups" grep -q '"kept": 4' "$tmp/out"
    run 0 "cook RAW/WithTexture.raw" "$CBVH" cook "$models/RAW/WithTexture.raw" "$tmp/wt.cbvh"
else
    skip "RAW assets: Debian's assimp-testmodels is not installed"
fi
if [ -n "$models" ] && [ -f "$models/invalid/OutOfMemory.off" ]; then
    # The header claims 35 billion vertices: the default memory limit stops the import.
    run 1 "cook invalid/OutOfMemory.off stops at the memory limit" "$CBVH" cook "$models/invalid/OutOfMemory.off" "$tmp/oom.cbvh" &&
        check "... and says how to raise the limit" grep -q "max-memory" "$tmp/err"
else
    skip "invalid/OutOfMemory.off: Debian's assimp-testmodels is not installed"
fi
run 2 "cook --max-memory x" "$CBVH" cook --max-memory x "$tmp/tri.obj" "$tmp/x.cbvh"

finish
