#!/bin/sh
# campaign.sh: a timed libFuzzer campaign for one cbvh fuzz target, from a fuzzing build.
# Usage: tests/fuzz/campaign.sh [--keep-going] TARGET SECONDS [BUILD_DIR]
#   TARGET is open, cook or import (import needs a build with the tool: no --disable-tools); BUILD_DIR (default .) was configured with
#   `configure --enable-fuzzing CC=clang --disable-tools` and built with `make tests/fuzz/fuzz_TARGET`.
#   --keep-going: libFuzzer's fork mode with -ignore_crashes, so the campaign runs for all of
#   SECONDS and collects every crash instead of stopping at the first one.
# The working corpus grows in BUILD_DIR/fuzz-corpus/TARGET (seeded from the
# committed corpus); crashes land in BUILD_DIR/fuzz-artifacts/TARGET and the
# log in BUILD_DIR/fuzz-TARGET.log, whose last lines give executions and cov/ft.
set -eu
usage="usage: campaign.sh [--keep-going] open|cook|import SECONDS [BUILD_DIR]"
mode=
if [ "${1:-}" = --keep-going ]; then
    mode="-fork=1 -ignore_crashes=1"
    shift
fi
target=${1:?$usage}
seconds=${2:?$usage}
build=${3:-.}
case "$target" in open|cook|import) ;; *) echo "campaign.sh: unknown target '$target'; $usage" >&2; exit 2 ;; esac
case "$seconds" in ''|*[!0-9]*) echo "campaign.sh: SECONDS must be a whole number, not '$seconds'" >&2; exit 2 ;; esac
here=$(cd "$(dirname "$0")" && pwd)
bin="$build/tests/fuzz/fuzz_$target"
[ -x "$bin" ] || { echo "campaign.sh: $bin not built (configure --enable-fuzzing CC=clang; make tests/fuzz/fuzz_$target)" >&2; exit 2; }
corpus="$build/fuzz-corpus/$target"
artifacts="$build/fuzz-artifacts/$target"
mkdir -p "$corpus" "$artifacts"
dict=
[ "$target" = open ] && dict="-dict=$here/cbvh.dict"
# import: the small PLY, OBJ, STL, OFF and glTF/GLB files of Debian's assimp-testmodels join the seeds, each
# behind the byte that picks its format (fuzz_import.c).
models=/usr/share/assimp/models
if [ "$target" = import ] && [ -d "$models" ]; then
    for pair in PLY:ply:0 OBJ:obj:1 STL:stl:2 OFF:off:3 glTF2:gltf:4 glTF2:glb:5; do
        folder=${pair%%:*} rest=${pair#*:}
        ext=${rest%%:*} byte=${rest#*:}
        find "$models/$folder" -type f -name "*.$ext" -size -8k | while read -r f; do
            seed="$corpus/testmodels-$(echo "$f" | tr '/' '_')"
            [ -e "$seed" ] || { printf "\\$(printf %o "$byte")"; cat "$f"; } >"$seed"
        done
    done
fi
# -max_len: small files reach every section; -timeout: a query that takes a
# second on a tiny file is a hang; -rss_limit_mb: the loader must not balloon.
"$bin" $mode $dict -max_total_time="$seconds" -max_len=8192 -timeout=5 -rss_limit_mb=1024 \
    -print_final_stats=1 -artifact_prefix="$artifacts/" \
    "$corpus" "$here/corpus/$target" >"$build/fuzz-$target.log" 2>&1 || status=$?
tail -n 25 "$build/fuzz-$target.log" | grep -E '^(#|stat::|Done)|ERROR|SUMMARY' | tail -n 8 || true
ls "$artifacts" | sed 's/^/artifact: /'
# One line to read a campaign by: executions (libFuzzer's final count, or in fork mode the last "#N:"
# progress line), seconds, findings (artifacts).
execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$build/fuzz-$target.log" | tail -n 1)
[ -n "$execs" ] || execs=$(grep -oE '^#[0-9]+' "$build/fuzz-$target.log" | tail -n 1 | tr -d '#')
findings=$(ls "$artifacts" | wc -l | tr -d ' ')
echo "campaign: $target: ${execs:-0} executions in $seconds s, $findings findings"
# keep-going mode can end with status 0 after crashes: any artifact fails the campaign
[ "$findings" = 0 ] || status=${status:-1}
[ "${status:-0}" = 0 ] || echo "campaign.sh: $target: failed (status ${status}); see $build/fuzz-$target.log" >&2
exit ${status:-0}
