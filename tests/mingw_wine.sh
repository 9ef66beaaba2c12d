#!/bin/sh
# mingw_wine.sh: cross-builds cbvh and its cmocka test programs for 64-bit Windows (MinGW-w64) and runs them under wine.
# Usage: tests/mingw_wine.sh [JOBS]   (from anywhere; the source tree is this script's ../)
# Needs gcc-mingw-w64-x86-64, libz-mingw-w64-dev, wine and wine64, and Debian's cmocka source package
# (`apt-get source cmocka`, which needs a deb-src line); exits 77 with a message when one is missing.
# cmocka is not packaged for MinGW: its source package is fetched and built once into
# ${XDG_CACHE_HOME:-~/.cache}/cbvh/mingw-cmocka (the source and its COPYING stay there), never into this tree.
# Exit status 0 when every test program passes under wine. Keeps the build only on failure.
set -eu
src=$(cd "$(dirname "$0")/.." && pwd)
jobs=${1:-2}
host=x86_64-w64-mingw32
start=$(date +%s)

missing=
command -v "$host-gcc" >/dev/null 2>&1 || missing="$missing gcc-mingw-w64-x86-64"
[ -f "/usr/$host/lib/libz.a" ] || missing="$missing libz-mingw-w64-dev"
command -v wine >/dev/null 2>&1 || missing="$missing wine wine64"
if [ -n "$missing" ]; then
    echo "mingw_wine.sh: SKIP: the Windows test build needs the Debian packages$missing"
    exit 77
fi

cache=${XDG_CACHE_HOME:-$HOME/.cache}/cbvh
cmocka=$cache/mingw-cmocka
if [ ! -f "$cmocka/lib/libcmocka.a" ]; then
    rm -rf "$cmocka.tmp"
    mkdir -p "$cmocka.tmp/src" "$cmocka.tmp/lib" "$cmocka.tmp/include"
    if ! (cd "$cmocka.tmp/src" && apt-get source -q cmocka >apt-source.log 2>&1); then
        echo "mingw_wine.sh: SKIP: 'apt-get source cmocka' failed: add a deb-src line for Debian's main archive" \
            "to /etc/apt/sources.list.d and run apt-get update (log: $cmocka.tmp/src/apt-source.log)"
        exit 77
    fi
    dir=$(find "$cmocka.tmp/src" -mindepth 1 -maxdepth 1 -type d -name 'cmocka-*' | head -n 1)
    # cmocka's own build is CMake; its one source file needs only these configuration macros (what its
    # ConfigureChecks.cmake finds for MinGW-w64), and the C99 printf so that %zu in messages works.
    "$host-gcc" -O2 -w -D__USE_MINGW_ANSI_STDIO=1 -DHAVE_SIGNAL_H -DHAVE_MALLOC_H -DHAVE_INTTYPES_H \
        -DHAVE_STRINGS_H -DHAVE_STRUCT_TIMESPEC -DHAVE_GCC_THREAD_LOCAL_STORAGE -I"$dir/include" \
        -c "$dir/src/cmocka.c" -o "$cmocka.tmp/cmocka.o"
    "$host-ar" rcs "$cmocka.tmp/lib/libcmocka.a" "$cmocka.tmp/cmocka.o"
    cp "$dir/include/cmocka.h" "$cmocka.tmp/include/"
    cp "$dir/COPYING" "$cmocka.tmp/COPYING"
    rm -rf "$cmocka"
    mv "$cmocka.tmp" "$cmocka"
fi

build=$(mktemp -d "${TMPDIR:-/tmp}/cbvh-mingw.XXXXXX")
log=$build/mingw.log
echo "mingw_wine.sh: building for $host in $build (log: $log)"
# One wine prefix per user, kept: creating it is wine's slow first start.
export WINEPREFIX="${CBVH_WINEPREFIX:-$cache/wine}" WINEDEBUG=-all
# libwinpthread-1.dll, for test_threads' pthreads, sits beside the MinGW libraries.
export WINEPATH="/usr/$host/lib"
# The dragon tests are Linux-only: under wine they would only repeat the native run, slower.
unset CBVH_DRAGON CBVH_DRAGON_MESH CBVH_BUNNY
# A tenth of the property tests' random queries (tests/support/layouts.h): what differs on Windows is
# the OS layer, the ABI and MinGW's code, which every layout, kernel, shape and scene still runs through;
# the full counts run in the native builds.
export CBVH_TEST_REPS="${CBVH_TEST_REPS:-10}"
mkdir -p "$WINEPREFIX"
status=0
(
    cd "$build"
    # -Wno-format: cmocka.h checks its printf formats as msvcrt's, which lacks %zu; ours use the C99 printf.
    PKG_CONFIG_LIBDIR="/usr/$host/lib/pkgconfig" "$src/configure" -q --host="$host" --disable-shared --disable-tools \
        CMOCKA_CFLAGS="-I$cmocka/include" CMOCKA_LIBS="$cmocka/lib/libcmocka.a" CFLAGS="-O2 -Wno-format" >>"$log" 2>&1
    make -j"$jobs" >>"$log" 2>&1
    built=$(date +%s)
    echo "mingw_wine.sh: built in $((built - start)) s; running the tests under wine"
    # The first wine start creates a new prefix: two tests starting at once on a new one race for its
    # server (seen on a fresh machine: "chdir to /tmp/wine-*/server-*: No such file or directory"). So the
    # prefix is made first, and one server stays up for the whole run.
    wineboot -i >>"$log" 2>&1
    wineserver -w
    wineserver -p >>"$log" 2>&1
    make -j"$jobs" check LOG_COMPILER=wine >>"$log" 2>&1
) || status=$?
end=$(date +%s)
wineserver -k 2>/dev/null || true
grep -E '^(PASS|FAIL|SKIP|XFAIL|XPASS|ERROR): ' "$log" 2>/dev/null || true
grep -E '^# (TOTAL|PASS|SKIP|XFAIL|FAIL|XPASS|ERROR):' "$build/test-suite.log" 2>/dev/null || true
if [ "$status" -ne 0 ]; then
    echo "mingw_wine.sh: FAILED after $((end - start)) s; see $log and $build/tests/*.log"
    exit 1
fi
echo "mingw_wine.sh: every Windows test program passed under wine; $((end - start)) s in all"
rm -rf "$build"
