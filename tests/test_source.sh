#!/bin/sh
# test_source.sh: rules of the source tree that a compiler does not check: the tools see the library only
# through include/cbvh.h and include/cbvh_internal.h (no other lib/ header, no field of struct cbvh_file).
top=${CBVH_TOP_SRCDIR:-$(cd "$(dirname "$0")/.." && pwd)}
failed=0

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

[ "$failed" = 0 ] || exit 1
exit 0
