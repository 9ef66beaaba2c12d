#!/bin/sh
# test_cmake.sh: the tiny project tests/cmake_consumer builds against cbvh::cbvh through CMake both ways and runs:
# find_package(cbvh CONFIG) of a cbvh installed by its CMake build (with the cooker: the consumer cooks a quad),
# and add_subdirectory of the source tree's cmake/ folder as a runtime-only build (CBVH_COOKER=OFF: the consumer
# reads the committed vector fileformat/good-quad-flat.cbvh, and cbvh.h hides the cooker's declarations).
# Skips (77) without cmake or with CBVH_SKIP_CMAKE_TEST=1. Writes only into a temporary folder.
set -eu
top=${CBVH_TOP_SRCDIR:-$(cd "$(dirname "$0")/.." && pwd)}
if [ "${CBVH_SKIP_CMAKE_TEST:-0}" = 1 ]; then
    echo "test_cmake.sh: SKIP: CBVH_SKIP_CMAKE_TEST=1 (tests/sanitize.sh, the runtime-only build and distcheck in tools/quickstart.sh: the main check runs it)"
    exit 77
fi
if ! command -v cmake >/dev/null 2>&1; then
    echo "test_cmake.sh: SKIP: cmake is not installed (Debian package cmake)"
    exit 77
fi
work=$(mktemp -d "${TMPDIR:-/tmp}/cbvh-cmake.XXXXXX")
log=$work/cmake.log
start=$(date +%s)

run() {
    if ! "$@" >>"$log" 2>&1; then
        tail -n 30 "$log"
        echo "test_cmake.sh: FAILED: $* (log: $log)"
        exit 1
    fi
}

# Both quads are cut along the same diagonal; the ray goes down through the first triangle, 1 above it.
expect_hit='2 triangles; hit triangle 0 at t = 1'
check_output() { # what, got, expected
    if [ "$2" != "$3" ]; then
        printf 'test_cmake.sh: FAILED: %s printed\n%s\ninstead of\n%s\n' "$1" "$2" "$3"
        exit 1
    fi
    echo "test_cmake.sh: $1: ok"
}

# optimised WHAT COMPILE_COMMANDS FLAG: every library source is compiled with FLAG (CMake adds no -O by itself).
optimised() {
    if grep '"command"' "$2" | grep '/lib/' | grep -v -q -e " $3 "; then
        echo "test_cmake.sh: FAILED: $1 compiles library sources without $3 ($2)"
        exit 1
    fi
    grep -q '/lib/' "$2" || { echo "test_cmake.sh: FAILED: $1: no library source in $2"; exit 1; }
    echo "test_cmake.sh: $1 compiles with $3: ok"
}

# 1. find_package(cbvh CONFIG) against a cbvh installed by its CMake build (the README's commands: no build
# type given, which means Release).
run cmake -S "$top/cmake" -B "$work/cbvh" -DCMAKE_INSTALL_PREFIX="$work/prefix" -DCMAKE_EXPORT_COMPILE_COMMANDS=ON
grep -q '^CMAKE_BUILD_TYPE:STRING=Release$' "$work/cbvh/CMakeCache.txt" ||
    { echo "test_cmake.sh: FAILED: the standalone build's default build type is not Release"; exit 1; }
optimised "the standalone build" "$work/cbvh/compile_commands.json" -O3
run cmake --build "$work/cbvh" -j 2
run cmake --install "$work/cbvh"
run cmake -S "$top/tests/cmake_consumer" -B "$work/installed" -DCMAKE_PREFIX_PATH="$work/prefix"
run cmake --build "$work/installed"
got=$("$work/installed/consumer" "$work/quad.cbvh")
check_output "find_package consumer" "$got" "cooker: yes
$expect_hit"

# 2. add_subdirectory of the source tree, runtime only.
run cmake -S "$top/tests/cmake_consumer" -B "$work/subdir" -DCBVH_SOURCE_DIR="$top" -DCBVH_COOKER=OFF \
    -DCMAKE_EXPORT_COMPILE_COMMANDS=ON
optimised "add_subdirectory into a project with no build type" "$work/subdir/compile_commands.json" -O2
run cmake --build "$work/subdir" -j 2
got=$("$work/subdir/consumer" "$top/fileformat/good-quad-flat.cbvh")
check_output "add_subdirectory runtime-only consumer" "$got" "cooker: no
$expect_hit"

# The runtime-only header declares no cooker: a call to cbvh_cook_options_init does not compile there,
# while the same file compiles against the installed full header.
printf '#include <cbvh.h>\nint main(void) { cbvh_cook_options o; cbvh_cook_options_init(&o, sizeof o); return 0; }\n' >"$work/uses_cooker.c"
run ${CC:-cc} -std=c11 -Werror=implicit-function-declaration -I"$work/prefix/include" -c "$work/uses_cooker.c" \
    -o "$work/uses_cooker.o"
if ${CC:-cc} -std=c11 -Werror=implicit-function-declaration -I"$top/include" -I"$work/subdir/cbvh/generated" \
    -c "$work/uses_cooker.c" -o "$work/uses_cooker.o" >>"$log" 2>&1; then
    echo "test_cmake.sh: FAILED: the runtime-only cbvh.h still declares the cooker"
    exit 1
fi
echo "test_cmake.sh: the runtime-only cbvh.h declares no cooker: ok"
echo "test_cmake.sh: both ways passed in $(($(date +%s) - start)) s"
rm -rf "$work"
