# tool_test_lib.sh: shared harness of the shell tests of the cbvh command (sourced, not run).
#
# The sourcing script sets `name` (used in messages and the temporary folder's name) first.
# Provides: CBVH (the built tool), tmp (a mktemp folder removed at exit), pass/fail/skip counters,
# run EXPECTED_STATUS NAME CMD..., check NAME CMD..., has_python, json_valid FILE, assimp_models, and finish.

CBVH=${CBVH_TOOL:-./tools/cbvh}
[ -x "$CBVH" ] || { echo "$name: $CBVH is not built"; exit 99; }

tmp=$(mktemp -d "${TMPDIR:-/tmp}/cbvh-$name.XXXXXX") || exit 99
trap 'chmod -R u+w "$tmp" 2>/dev/null; rm -rf "$tmp"' EXIT INT TERM

passed=0
failed=0
skipped=0

pass() { passed=$((passed + 1)); echo "ok   $1"; }
fail() { failed=$((failed + 1)); echo "FAIL $1"; }
skip() { skipped=$((skipped + 1)); echo "skip $1"; }

# run EXPECTED_STATUS NAME CMD...: runs CMD with stdout/stderr in $tmp/out, $tmp/err; checks the status.
run() {
    expect=$1
    label=$2
    shift 2
    "$@" >"$tmp/out" 2>"$tmp/err" </dev/null
    status=$?
    if [ "$status" -eq "$expect" ]; then
        pass "$label"
        return 0
    fi
    fail "$label (exit $status, expected $expect)"
    sed 's/^/     | /' "$tmp/err" | head -5
    return 1
}

# check NAME CMD...: passes when the command succeeds.
check() {
    label=$1
    shift
    if "$@"; then pass "$label"; else fail "$label"; fi
}

has_python=0
command -v python3 >/dev/null 2>&1 && has_python=1
json_valid() { python3 -m json.tool "$1" >/dev/null 2>&1; }

# assimp_models: prints the folder of Debian's assimp-testmodels ($CBVH_ASSIMP_MODELS first), or nothing.
assimp_models() {
    m=${CBVH_ASSIMP_MODELS:-}
    if [ -z "$m" ] && command -v dpkg >/dev/null 2>&1; then
        m=$(dpkg -L assimp-testmodels 2>/dev/null | grep '/models$' | head -1)
    fi
    [ -z "$m" ] && [ -d /usr/share/assimp/models ] && m=/usr/share/assimp/models
    echo "$m"
}

# The closing line counts the checks; the exit status tells automake.
finish() {
    echo "$name: $passed passed, $failed failed, $skipped skipped"
    [ "$failed" -eq 0 ] || exit 1
    exit 0
}
