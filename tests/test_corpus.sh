#!/bin/sh
# test_corpus.sh: `cbvh cook` over every file of Debian's assimp-testmodels (hundreds of files in dozens of
# formats, valid and deliberately broken). Each file either cooks into a file that `cbvh verify` accepts,
# or exits 1 with a message that names it. No crash, no hang: each cook runs with a time limit
# (CBVH_CORPUS_SECONDS, default 60) and an address-space limit (ulimit -v, 3 GiB) so a hostile asset
# costs a bounded amount; two cooks run at once.
#
# Environment: as tests/test_tool.sh (CBVH_TOOL, CBVH_ASSIMP_MODELS). Skips when the models are absent.

name=test_corpus.sh
. "$(dirname "$0")/tool_test_lib.sh"

if [ "${CBVH_SKIP_CORPUS:-0}" = 1 ]; then
    echo "$name: SKIP: CBVH_SKIP_CORPUS=1 (quickstart's distcheck: the corpus ran in the main check)"
    exit 77
fi
models=$(assimp_models)
if [ -z "$models" ] || [ ! -d "$models" ]; then
    skip "the corpus: Debian's assimp-testmodels is not installed (apt-get install assimp-testmodels)"
    finish
fi
command -v timeout >/dev/null 2>&1 || { skip "the corpus: timeout(1) not found"; finish; }
limit=${CBVH_CORPUS_SECONDS:-60}

# One cook: prints "STATUS MILLISECONDS FILE" and keeps the messages beside the results.
cat >"$tmp/one.sh" <<'ONE'
f=$1
key=$(printf '%s' "$f" | cksum | tr ' ' _)
start=$(date +%s%N)
( ulimit -v 3145728 2>/dev/null; exec timeout -s KILL "$LIMIT" "$CBVH" cook --quiet "$f" "$OUT/$key.cbvh" ) \
    >/dev/null 2>"$OUT/$key.err"
status=$?
if [ "$status" = 0 ] && ! "$CBVH" verify "$OUT/$key.cbvh" >"$OUT/$key.verify" 2>&1; then
    status=verify
fi
rm -f "$OUT/$key.cbvh"
echo "$status $(( ($(date +%s%N) - start) / 1000000 )) $key $f"
ONE
mkdir "$tmp/out.d"
t0=$(date +%s)
find "$models" -type f -print0 | sort -z |
    CBVH="$CBVH" OUT="$tmp/out.d" LIMIT="$limit" xargs -0 -n1 -P2 sh "$tmp/one.sh" >"$tmp/results"
seconds=$(($(date +%s) - t0))

total=$(wc -l <"$tmp/results")
cooked=$(awk '$1 == "0"' "$tmp/results" | wc -l)
rejected=$(awk '$1 == "1"' "$tmp/results" | wc -l)
check "every corpus file was tried ($total files)" test "$total" -eq "$(find "$models" -type f | wc -l)"
check "at least 200 files cook" test "$cooked" -ge 200
# Anything but 0 and 1 is a defect: 137 a kill at the time limit, 128+N a signal, 2 a usage or I/O error,
# "verify" a cooked file the loader refuses.
awk '$1 != "0" && $1 != "1"' "$tmp/results" >"$tmp/bad"
if [ -s "$tmp/bad" ]; then
    fail "$(wc -l <"$tmp/bad") files neither cooked nor were rejected with exit status 1:"
    sed 's/^/     | /' "$tmp/bad" | head -20
else
    pass "no crash, hang or other exit status over the corpus"
fi
# Every rejection names its file.
unnamed=0
while read -r status ms key file; do
    [ "$status" = 1 ] || continue
    grep -qF "$file" "$tmp/out.d/$key.err" || { unnamed=$((unnamed + 1)); echo "     | no file name: $file"; }
done <"$tmp/results"
check "every rejection names its file" test "$unnamed" -eq 0
echo "corpus: $total files in $seconds s: $cooked cooked and verified, $rejected rejected (exit 1);" \
    "slowest: $(sort -k2 -n -r "$tmp/results" | head -1 | awk '{print $2 " ms " $4}')"
echo "corpus: rejections by reason:"
awk '$1 == "1" { print $3 }' "$tmp/results" | while read -r key; do
    sed -e 's/^cbvh cook: .*: \(assimp cannot read it: \)\{0,1\}//' "$tmp/out.d/$key.err" | cut -c1-60
done | sort | uniq -c | sort -rn | head -12
finish
