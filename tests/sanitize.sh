#!/bin/sh
# sanitize.sh: builds cbvh again with ASan + UBSan in a temporary folder and runs `make check` there
# (which replays the fuzz corpora) and the finding inputs; then builds with ThreadSanitizer and runs the
# programs that start threads (test_threads: concurrent queries on one file; test_cook: the parallel build).
# Usage: tests/sanitize.sh [JOBS]   (from anywhere; the source tree is this script's ../)
# Exit status 0 when every test passes under the sanitizers. Keeps the build only on failure.
set -eu
src=$(cd "$(dirname "$0")/.." && pwd)
jobs=${1:-2}
build=$(mktemp -d "${TMPDIR:-/tmp}/cbvh-sanitize.XXXXXX")
start=$(date +%s)
log="$build/sanitize.log"
echo "sanitize.sh: building in $build (log: $log)"
# abort_on_error gives a core-style stop; detect_leaks catches leaks the OOM loops miss
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
# The CMake consumer test builds without sanitizers: the plain make check runs it.
export CBVH_SKIP_CMAKE_TEST=1
# A tenth of the property tests' random queries (tests/support/layouts.h): the sanitizers still see every
# layout, walk kernel, shape, scene and cook variant, at a tenth of the cost (almost all of it the
# brute-force reference's, instrumented too); the plain builds run the full counts. The corrupted files,
# allocation failures and fuzz corpora are not cut. test_threads' ASan run takes 1 s a layout (the
# ThreadSanitizer run below keeps 3 s).
export CBVH_TEST_REPS="${CBVH_TEST_REPS:-10}"
# The cooked dragon's tests (CBVH_DRAGON: 871K triangles) run in the plain builds; here they would cost
# minutes for code paths the smaller scenes take too.
unset CBVH_DRAGON
status=0
(
    cd "$build"
    "$src/configure" -q --enable-sanitizers --disable-tools --disable-shared CFLAGS="-O1 -g" >>"$log" 2>&1
    make -j"$jobs" >>"$log" 2>&1
    CBVH_THREAD_SECONDS="${CBVH_THREAD_SECONDS:-1}" make -j"$jobs" check >>"$log" 2>&1
) || status=$?
if [ "$status" -eq 0 ]; then
    # finding inputs are replayed too: they must not crash even before their bugs are fixed
    "$build/tests/fuzz/replay_cook" "$src/tests/fuzz/findings" >>"$log" 2>&1 || status=$?
fi
asan_end=$(date +%s)
if [ "$status" -eq 0 ]; then
    # ThreadSanitizer: any data race is a failure (halt_on_error), with the default 4 query threads.
    export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1"
    mkdir "$build/tsan"
    (
        cd "$build/tsan"
        "$src/configure" -q --enable-sanitizers=thread --disable-tools --disable-shared CFLAGS="-O1 -g" >>"$log" 2>&1
        threaded="tests/test_threads tests/test_cook"
        make -j"$jobs" check TESTS="$threaded" check_PROGRAMS="$threaded" >>"$log" 2>&1
    ) || status=$?
    cat "$build/tsan/tests/test_threads.log" >>"$log" 2>/dev/null || true
fi
end=$(date +%s)
grep -E '^(PASS|FAIL|SKIP|XFAIL|XPASS|ERROR): ' "$log" 2>/dev/null || true
grep -E '^# (TOTAL|PASS|SKIP|XFAIL|FAIL|XPASS|ERROR):' "$build/test-suite.log" 2>/dev/null || true
grep -E '^threads: ' "$log" 2>/dev/null | sed 's/^/ThreadSanitizer: /' || true
if [ "$status" -ne 0 ]; then
    echo "sanitize.sh: FAILED after $((end - start)) s; see $log and $build/tests/*.log, $build/tsan/tests/*.log"
    exit 1
fi
echo "sanitize.sh: all tests passed under ASan+UBSan in $((asan_end - start)) s and the threaded ones under ThreadSanitizer in $((end - asan_end)) s"
rm -rf "$build"
