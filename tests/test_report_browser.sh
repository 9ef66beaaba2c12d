#!/bin/sh
# test_report_browser.sh: `cbvh report --html` in a real browser (headless Chromium): no console or page errors, every plot element, labels as laid out, focus details, a screenshot.
#
# Environment (set by `make check` through AM_TESTS_ENVIRONMENT):
#   CBVH_TOOL       the built tools/cbvh
#   CBVH_CHROMIUM   the browser to use (default: chromium, chromium-browser or google-chrome on the PATH)
# Skips (exit 77) without Chromium or python3. Leaves the screenshot in tests/report_browser.png of the build tree.

name=test_report_browser.sh
. "$(dirname "$0")/tool_test_lib.sh"

if [ "${CBVH_SKIP_BROWSER:-0}" = 1 ]; then
    echo "$name: SKIP: CBVH_SKIP_BROWSER=1 (quickstart's distcheck: the browser test ran in the main check)"
    exit 77
fi
chromium=${CBVH_CHROMIUM:-}
if [ -z "$chromium" ]; then
    for c in chromium chromium-browser google-chrome; do
        if command -v "$c" >/dev/null 2>&1; then chromium=$c; break; fi
    done
fi
if [ -z "$chromium" ]; then
    echo "$name: SKIP: Chromium not found (Debian: apt-get install chromium; or set CBVH_CHROMIUM)"
    exit 77
fi
if [ "$has_python" != 1 ]; then
    echo "$name: SKIP: python3 not found (it drives Chromium over the DevTools pipe)"
    exit 77
fi

shot=tests/report_browser.png
mkdir -p tests
run 0 "report --html on two scenes" "$CBVH" report --gen sphere:3000 --gen terrain:2000 --rays 3000 --sample 300 \
    --reps 1 --quiet --html "$tmp/report.html" &&
    check "Chromium: no console errors, six plots per mesh with every point, label and detail box, labels apart and inside" \
        python3 "$(dirname "$0")/browser_check.py" "$chromium" "$tmp/report.html" "$shot" 2 18 &&
    echo "     screenshot: $(pwd)/$shot"
finish
