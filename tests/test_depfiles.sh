#!/bin/sh
# test_depfiles.sh: `cbvh cook --depfile` and `--depfiles` as make trusts them: a depfile never replaces the
# asset or the output; it lists side files looked for and not found (a missing .mtl) as well as those found,
# also for .obj.gz assets, with an empty rule per dependency (gcc -MP) so deleting one does not break make and
# restoring one re-cooks; when the depfile or the cook fails, neither file changes; a batch writes OUT.d per
# asset.
#
# Environment: as tests/test_tool.sh (CBVH_TOOL). The make part skips without make.

name=test_depfiles.sh
. "$(dirname "$0")/tool_test_lib.sh"

# A tetrahedron whose material comes from tet.mtl.
mkdir "$tmp/a"
{
    printf 'mtllib tet.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nusemtl red\n'
    printf 'f 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n'
} >"$tmp/a/tet.obj"
printf 'newmtl red\nKd 1 0 0\n' >"$tmp/a/tet.mtl"
cp "$tmp/a/tet.obj" "$tmp/a/keep.obj"

# Item 4: the depfile is neither the asset nor the output, by any name.
run 2 "--depfile IN is refused" "$CBVH" cook --quiet --depfile "$tmp/a/tet.obj" "$tmp/a/tet.obj" "$tmp/o.cbvh"
check "... the asset is unchanged" cmp -s "$tmp/a/tet.obj" "$tmp/a/keep.obj"
check "... no output" test ! -e "$tmp/o.cbvh"
ln -s "$tmp/a/tet.obj" "$tmp/link.obj"
run 2 "--depfile a link to IN is refused" "$CBVH" cook --quiet --depfile "$tmp/link.obj" "$tmp/a/tet.obj" "$tmp/o.cbvh"
check "... the asset is unchanged" cmp -s "$tmp/a/tet.obj" "$tmp/a/keep.obj"
run 2 "--depfile OUT (not there yet, named another way) is refused" "$CBVH" cook --quiet --depfile "$tmp/./o.cbvh" \
    "$tmp/a/tet.obj" "$tmp/o.cbvh"
check "... no output" test ! -e "$tmp/o.cbvh"
"$CBVH" cook --quiet "$tmp/a/tet.obj" "$tmp/o.cbvh" >/dev/null
cp "$tmp/o.cbvh" "$tmp/o-before.cbvh"
run 2 "--depfile OUT (there) is refused" "$CBVH" cook --quiet --layout binary --depfile "$tmp/o.cbvh" "$tmp/a/tet.obj" \
    "$tmp/o.cbvh"
check "... the output is unchanged" cmp -s "$tmp/o.cbvh" "$tmp/o-before.cbvh"

# Item 7: a depfile that cannot be written changes nothing; a cook that fails leaves the old depfile.
if [ -e /dev/full ]; then
    run 2 "--depfile /dev/full" "$CBVH" cook --quiet --layout binary --depfile /dev/full "$tmp/a/tet.obj" "$tmp/o.cbvh"
    check "... the output is unchanged" cmp -s "$tmp/o.cbvh" "$tmp/o-before.cbvh"
fi
run 2 "--depfile in a missing folder" "$CBVH" cook --quiet --layout binary --depfile "$tmp/none/o.d" "$tmp/a/tet.obj" \
    "$tmp/o.cbvh"
check "... the output is unchanged" cmp -s "$tmp/o.cbvh" "$tmp/o-before.cbvh"
check "... the message names the depfile" grep -q "$tmp/none/o.d: cannot write the depfile" "$tmp/err"
printf 'old rule\n' >"$tmp/old.d"
mkdir "$tmp/folder"
run 2 "a cook that fails after the depfile was written (OUT is a folder)" "$CBVH" cook --quiet --depfile "$tmp/old.d" \
    "$tmp/a/tet.obj" "$tmp/folder"
check "... the previous depfile is back" test "$(cat "$tmp/old.d")" = "old rule"
run 2 "... and with no previous depfile" "$CBVH" cook --quiet --depfile "$tmp/new.d" "$tmp/a/tet.obj" "$tmp/folder"
check "... none is left" test ! -e "$tmp/new.d"
check "... nor a temporary file" test -z "$(ls -A "$tmp" | grep -e '\.tmp-' -e '\.old-')"

# Item 5: found and missing side files, each with an empty rule.
run 0 "--depfile with the .mtl present" "$CBVH" cook --quiet --depfile "$tmp/o.d" "$tmp/a/tet.obj" "$tmp/o.cbvh"
check "... lists the asset and its .mtl" grep -q "$tmp/a/tet.obj.*" "$tmp/o.d"
check "... an empty rule for the .mtl" grep -q "^$tmp/a/tet.mtl:\$" "$tmp/o.d"
check "... none for the asset" sh -c "! grep -q '^$tmp/a/tet.obj:' '$tmp/o.d'"
mv "$tmp/a/tet.mtl" "$tmp/tet.mtl.away"
run 0 "--depfile with the .mtl missing" "$CBVH" cook --quiet --depfile "$tmp/o.d" "$tmp/a/tet.obj" "$tmp/o.cbvh"
check "... still lists the .mtl (looked for, not found)" grep -q "^$tmp/a/tet.mtl:\$" "$tmp/o.d"
check "... and warns about it" grep -q "tet.mtl', which was not found" "$tmp/err"
mv "$tmp/tet.mtl.away" "$tmp/a/tet.mtl"

# Item 6: an .obj.gz asset's .mtl, found and missing.
gzip -c "$tmp/a/tet.obj" >"$tmp/a/zipped.obj.gz"
run 0 "--depfile of an .obj.gz" "$CBVH" cook --quiet --depfile "$tmp/z.d" "$tmp/a/zipped.obj.gz" "$tmp/z.cbvh"
check "... lists its .mtl" grep -q "^$tmp/a/tet.mtl:\$" "$tmp/z.d"
mv "$tmp/a/tet.mtl" "$tmp/tet.mtl.away"
run 0 "an .obj.gz with its .mtl missing" "$CBVH" cook --json --depfile "$tmp/z.d" "$tmp/a/zipped.obj.gz" "$tmp/z.cbvh"
check "... warns about it" grep -q "tet.mtl', which was not found" "$tmp/err"
check "... lists it in missing_files" grep -q "\"$tmp/a/tet.mtl\"" "$tmp/out"
check "... and in the depfile" grep -q "^$tmp/a/tet.mtl:\$" "$tmp/z.d"
mv "$tmp/tet.mtl.away" "$tmp/a/tet.mtl"

# Item 8: a batch writes OUT.d beside each output; --depfile (one file) is refused there.
mkdir "$tmp/batch"
cp "$tmp/a/tet.obj" "$tmp/a/other.obj"
run 0 "a batch with --depfiles" "$CBVH" cook --depfiles --jobs 2 --output-dir "$tmp/batch" "$tmp/a/tet.obj" \
    "$tmp/a/other.obj"
check "... one depfile per asset, naming its output, asset and .mtl" sh -c \
    "grep -q '^$tmp/batch/tet.cbvh: $tmp/a/tet.obj' '$tmp/batch/tet.cbvh.d' &&
     grep -q '^$tmp/batch/other.cbvh: $tmp/a/other.obj' '$tmp/batch/other.cbvh.d' &&
     grep -q '^$tmp/a/tet.mtl:\$' '$tmp/batch/other.cbvh.d'"
run 2 "a batch with --depfile FILE" "$CBVH" cook --depfile "$tmp/x.d" --output-dir "$tmp/batch" "$tmp/a/tet.obj"

# make: restoring a missing .mtl re-cooks; deleting a listed side file does not break the build.
MAKE_PROGRAM=${MAKE:-make}
if command -v "$MAKE_PROGRAM" >/dev/null 2>&1; then
    unset MAKEFLAGS MFLAGS MAKELEVEL
    case "$CBVH" in /*) ;; *) CBVH="$(pwd)/$CBVH" ;; esac
    mkdir "$tmp/m" "$tmp/m/assets"
    cp "$tmp/a/tet.obj" "$tmp/m/assets/"
    printf 'all: cooked.cbvh\ncooked.cbvh: assets/tet.obj\n\t$(CBVH) cook --quiet --depfile $@.d $< $@\n-include cooked.cbvh.d\n' \
        >"$tmp/m/Makefile"
    run 0 "make, the .mtl missing" "$MAKE_PROGRAM" -C "$tmp/m" CBVH="$CBVH"
    sleep 1
    cp "$tmp/a/tet.mtl" "$tmp/m/assets/tet.mtl"
    run 0 "make after the .mtl appears" "$MAKE_PROGRAM" -C "$tmp/m" CBVH="$CBVH"
    check "... re-cooks" grep -q "cbvh cook" "$tmp/out"
    check "... with the material" sh -c "'$CBVH' info '$tmp/m/cooked.cbvh' | grep -q red"
    run 0 "make again" "$MAKE_PROGRAM" -C "$tmp/m" CBVH="$CBVH"
    check "... cooks nothing" sh -c "! grep -q 'cbvh cook' '$tmp/out'"
    rm "$tmp/m/assets/tet.mtl"
    run 0 "make after the .mtl is deleted (no 'No rule to make target')" "$MAKE_PROGRAM" -C "$tmp/m" CBVH="$CBVH"
    check "... re-cooks" grep -q "cbvh cook" "$tmp/out"
else
    skip "make: not installed"
fi
finish
