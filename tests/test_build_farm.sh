#!/bin/sh
# test_build_farm.sh: cooking as a pure function of input bytes and options, fanned out by make: the
# README's make rule with --depfile, run with make -j2 over a folder of assets. A second run does
# nothing; touching an asset's .mtl re-cooks that asset only; the outputs are byte-identical to single
# cooks.
#
# Environment: as tests/test_tool.sh (CBVH_TOOL). Skips without make.

name=test_build_farm.sh
. "$(dirname "$0")/tool_test_lib.sh"

MAKE_PROGRAM=${MAKE:-make}
command -v "$MAKE_PROGRAM" >/dev/null 2>&1 || { skip "build farm: make not found"; finish; }
case "$CBVH" in /*) ;; *) CBVH="$(pwd)/$CBVH" ;; esac
# The recipes' echo tells what make ran: drop the flags of a surrounding make (make -s check).
unset MAKEFLAGS MFLAGS MAKELEVEL

mkdir "$tmp/assets" "$tmp/single"
for k in 1 2 3; do
    {
        printf 'mtllib tet%s.mtl\n' "$k"
        printf 'v 0 0 0\nv %s 0 0\nv 0 %s 0\nv 0 0 %s\nusemtl m\n' "$k" "$k.5" "$k.25"
        printf 'f 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n'
    } >"$tmp/assets/tet$k.obj"
    printf 'newmtl m\nKd 0.%s 0 0\n' "$k" >"$tmp/assets/tet$k.mtl"
    "$CBVH" cook --quiet "$tmp/assets/tet$k.obj" "$tmp/single/tet$k.cbvh" >/dev/null
done
# The README's rule (keep the two in step).
cat >"$tmp/Makefile" <<'MK'
ASSETS := $(wildcard assets/*.obj)
COOKED := $(ASSETS:assets/%.obj=cooked/%.cbvh)
all: $(COOKED)
cooked/%.cbvh: assets/%.obj | cooked
	$(CBVH) cook --quiet --depfile $@.d $< $@ >/dev/null
cooked:
	mkdir -p $@
-include $(COOKED:=.d)
MK

run 0 "make -j2 cooks every asset" "$MAKE_PROGRAM" -C "$tmp" -j2 CBVH="$CBVH"
same=0
for k in 1 2 3; do cmp -s "$tmp/single/tet$k.cbvh" "$tmp/cooked/tet$k.cbvh" && same=$((same + 1)); done
check "... outputs byte-identical to single cooks" test "$same" -eq 3
check "... each depfile names the asset and its .mtl" grep -q "tet2.obj.*tet2.mtl" "$tmp/cooked/tet2.cbvh.d"
run 0 "a second make" "$MAKE_PROGRAM" -C "$tmp" -j2 CBVH="$CBVH"
check "... cooks nothing" sh -c "! grep -q 'cbvh cook' '$tmp/out'"
# make compares modification times: step the clock past the outputs' second.
sleep 1
touch "$tmp/assets/tet2.mtl"
run 0 "make after touching tet2.mtl" "$MAKE_PROGRAM" -C "$tmp" -j2 CBVH="$CBVH"
check "... re-cooks tet2 only" test "$(grep -c 'cbvh cook' "$tmp/out")" -eq 1 -a "$(grep -c 'tet2.obj' "$tmp/out")" -eq 1
finish
