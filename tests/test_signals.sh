#!/bin/sh
# test_signals.sh: commands stopped by a signal leave nothing behind: `cbvh bench` and `cbvh demo` remove their
# temporary files on SIGTERM and SIGHUP; a batch cook (`cook --jobs 2`) stopped by SIGTERM passes it to its
# cooks, so none of them goes on to write its output.
#
# Environment: as tests/test_tool.sh (CBVH_TOOL). (Background commands of a non-interactive shell ignore
# SIGINT, so SIGINT, handled by the same code, is not sent here.)

name=test_signals.sh
. "$(dirname "$0")/tool_test_lib.sh"

# wait_for SECONDS TEST...: polls TEST every 50 ms; fails after SECONDS.
wait_for() {
    limit=$(($1 * 20))
    shift
    n=0
    until "$@"; do
        n=$((n + 1))
        [ "$n" -ge "$limit" ] && return 1
        sleep 0.05
    done
}
some_file() { [ -n "$(find "$1" -type f 2>/dev/null | head -1)" ]; }

# Item 9: bench's cooked temporary file and demo's folder go on SIGTERM and SIGHUP.
for sig in TERM HUP; do
    mkdir "$tmp/bench-$sig"
    TMPDIR="$tmp/bench-$sig" "$CBVH" bench --quiet --no-peers --rays 2000000 --gen sphere:20000 >/dev/null 2>&1 &
    pid=$!
    if wait_for 60 some_file "$tmp/bench-$sig"; then
        kill -s $sig $pid
        wait $pid
        check "bench, SIG$sig: its temporary file is gone" test -z "$(ls -A "$tmp/bench-$sig")"
    else
        kill $pid 2>/dev/null
        wait $pid
        fail "bench, SIG$sig: no temporary file appeared"
    fi
    mkdir "$tmp/demo-$sig"
    TMPDIR="$tmp/demo-$sig" "$CBVH" demo --quiet >/dev/null 2>&1 &
    pid=$!
    if wait_for 60 some_file "$tmp/demo-$sig"; then
        kill -s $sig $pid
        wait $pid
        status=$?
        # the demo may have finished on its own first: then it removed its files as usual
        check "demo, SIG$sig (exit $status): its temporary folder is gone" test -z "$(ls -A "$tmp/demo-$sig")"
    else
        kill $pid 2>/dev/null
        wait $pid
        fail "demo, SIG$sig: no temporary file appeared"
    fi
done

# Item 10: SIGTERM to a batch's parent. The assets are FIFOs, so each cook waits in its import until the
# test writes them; after the batch is stopped, writing them must find no reader left.
if mkfifo "$tmp/a.obj" "$tmp/b.obj" 2>/dev/null && [ -d /proc/self ]; then
    mkdir "$tmp/batch"
    "$CBVH" cook --jobs 2 --output-dir "$tmp/batch" "$tmp/a.obj" "$tmp/b.obj" >"$tmp/out" 2>"$tmp/err" &
    batch=$!
    children_of() {
        for st in /proc/[0-9]*/stat; do
            fields=$(cat "$st" 2>/dev/null) || continue
            # shellcheck disable=SC2086
            set -- $fields
            [ "${4:-}" = "$batch" ] && echo "$1"
        done
    }
    two_cooks() { [ "$(children_of | wc -l)" -ge 2 ]; }
    if wait_for 30 two_cooks; then
        cooks=$(children_of)
        kill -s TERM $batch
        wait $batch
        status=$?
        check "a batch stopped by SIGTERM ends by it (exit $status)" test "$status" -eq 143
        alive=0
        for c in $cooks; do kill -0 "$c" 2>/dev/null && alive=$((alive + 1)); done
        check "... its cooks are gone" test "$alive" -eq 0
        # Feed the FIFOs (a writer finds no reader and gives up after a moment).
        printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' >"$tmp/tri.obj"
        for f in a b; do
            (cat "$tmp/tri.obj" >"$tmp/$f.obj") &
            writer=$!
            sleep 1
            kill $writer 2>/dev/null
            wait $writer 2>/dev/null
        done
        sleep 1
        check "... and no output is written afterwards" test -z "$(ls -A "$tmp/batch")"
    else
        kill -s KILL $batch 2>/dev/null
        wait $batch
        fail "a batch stopped by SIGTERM: its cooks did not start"
    fi
else
    skip "batch and SIGTERM: mkfifo or /proc unavailable"
fi
finish
