#!/bin/sh
# test_source.sh: rules of the source tree that a compiler does not check: the tools see the library only
# through include/cbvh.h and include/cbvh_internal.h (no other lib/ header, no field of struct cbvh_file),
# the library's includes and calls between its objects make no circle (tools/check_circles.py, on the
# objects of the build folder it runs in), and every C file is formatted as .clang-format says
# (tools/check_format.sh). Skips the circle check without python3 and nm, the format check without
# clang-format.
top=${CBVH_TOP_SRCDIR:-$(cd "$(dirname "$0")/.." && pwd)}
failed=0
skipped=0

private=$(grep -rnE '#include "(common|layout|load|query|cook|inspect)/' "$top/tools" --include='*.[ch]' --include='*.cpp')
if [ -n "$private" ]; then
    echo "FAIL tools include private library headers (use include/cbvh_internal.h):"
    echo "$private" | sed 's/^/     | /'
    failed=1
else
    echo "ok   tools include no private library header"
fi
fields=$(grep -rnE 'struct cbvh_file\b' "$top/tools" --include='*.[ch]' --include='*.cpp')
if [ -n "$fields" ]; then
    echo "FAIL tools name the private struct cbvh_file:"
    echo "$fields" | sed 's/^/     | /'
    failed=1
else
    echo "ok   tools name no private struct"
fi

if command -v python3 >/dev/null 2>&1 && command -v nm >/dev/null 2>&1; then
    python3 "$top/tools/check_circles.py" "$top" "$PWD" || failed=1
else
    echo "skip circle check: python3 or nm not found"
    skipped=1
fi

status=0
sh "$top/tools/check_format.sh" || status=$?
case "$status" in
0) echo "ok   every C file is formatted" ;;
77) echo "skip format check: clang-format not found"; skipped=1 ;;
*) echo "FAIL C files not formatted"; failed=1 ;;
esac

[ "$failed" = 0 ] || exit 1
[ "$skipped" = 0 ] || exit 77
exit 0
