#!/bin/sh
# campaign.sh: a timed libFuzzer campaign for one cbvh fuzz target, from a fuzzing build.
# Usage: tests/fuzz/campaign.sh TARGET SECONDS [BUILD_DIR]
#   TARGET is open or cook; BUILD_DIR (default .) was configured with
#   `configure --enable-fuzzing CC=clang --disable-tools` and built with `make tests/fuzz/fuzz_TARGET`.
# The working corpus grows in BUILD_DIR/fuzz-corpus/TARGET (seeded from the
# committed corpus); crashes land in BUILD_DIR/fuzz-artifacts/TARGET and the
# log in BUILD_DIR/fuzz-TARGET.log, whose last lines give executions and cov/ft.
set -eu
target=${1:?usage: campaign.sh open|cook SECONDS [BUILD_DIR]}
seconds=${2:?usage: campaign.sh open|cook SECONDS [BUILD_DIR]}
build=${3:-.}
here=$(cd "$(dirname "$0")" && pwd)
bin="$build/tests/fuzz/fuzz_$target"
[ -x "$bin" ] || { echo "campaign.sh: $bin not built (configure --enable-fuzzing CC=clang; make tests/fuzz/fuzz_$target)" >&2; exit 2; }
corpus="$build/fuzz-corpus/$target"
artifacts="$build/fuzz-artifacts/$target"
mkdir -p "$corpus" "$artifacts"
dict=
[ "$target" = open ] && dict="-dict=$here/cbvh.dict"
# -max_len: small files reach every section; -timeout: a query that takes a
# second on a tiny file is a hang; -rss_limit_mb: the loader must not balloon.
"$bin" $dict -max_total_time="$seconds" -max_len=8192 -timeout=5 -rss_limit_mb=1024 \
    -print_final_stats=1 -artifact_prefix="$artifacts/" \
    "$corpus" "$here/corpus/$target" >"$build/fuzz-$target.log" 2>&1 || status=$?
tail -n 25 "$build/fuzz-$target.log" | grep -E '^(#|stat::|Done)|ERROR|SUMMARY' || true
ls "$artifacts" | sed 's/^/artifact: /'
exit ${status:-0}
