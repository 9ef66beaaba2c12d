#!/bin/sh
# test_bench.sh: `cbvh bench` and `cbvh report` on tiny generated scenes: exit codes, help, tables, JSON, SVG, peer agreement.
#
# Environment (set by `make check` through AM_TESTS_ENVIRONMENT):
#   CBVH_TOOL     the built tools/cbvh
#   CBVH_TINYBVH  yes when configure was given tinybvh (--with-tinybvh=DIR): its rows are then expected
#   CBVH_JOLT     yes when configure was given Jolt (--with-jolt=PREFIX): its rows are then expected
# Writes only into a mktemp folder, removed at exit. JSON and SVG checks need python3 (skipped without it).

name=test_bench.sh
. "$(dirname "$0")/tool_test_lib.sh"

# ---- usage ------------------------------------------------------------------------------------

run 0 "bench --help" "$CBVH" bench --help && check "... prints the usage" grep -q '^Usage: cbvh bench' "$tmp/out"
run 0 "report --help" "$CBVH" report --help && check "... prints the usage" grep -q '^Usage: cbvh report' "$tmp/out"
run 2 "bench without input" "$CBVH" bench
run 2 "bench with INPUT and --gen" "$CBVH" bench x.obj --gen sphere:100
run 2 "bench --rays 0" "$CBVH" bench --gen sphere:100 --rays 0
run 2 "bench --threads abc" "$CBVH" bench --gen sphere:100 --threads abc
run 2 "bench --threads 1,0" "$CBVH" bench --gen sphere:100 --threads 1,0
run 2 "bench --threads 1," "$CBVH" bench --gen sphere:100 --threads 1,
run 2 "bench --shapes x" "$CBVH" bench --gen sphere:100 --shapes x
run 2 "bench with an unknown option" "$CBVH" bench --gen sphere:100 --frobnicate
run 2 "bench with a bad generated scene" "$CBVH" bench --gen pyramid:5 &&
    check "... says what is wrong" grep -q 'pyramid:5' "$tmp/err"
run 2 "bench of a missing file" "$CBVH" bench "$tmp/missing.obj" &&
    check "... names the file" grep -q 'missing.obj' "$tmp/err"
printf 'this is not a mesh\n' >"$tmp/junk.obj"
run 1 "bench of a file that is not a mesh" "$CBVH" bench "$tmp/junk.obj"
run 2 "report without mesh" "$CBVH" report
run 2 "report --reps 0" "$CBVH" report --gen sphere:100 --reps 0

# ---- bench ------------------------------------------------------------------------------------

run 0 "bench --gen sphere:2000" "$CBVH" bench --gen sphere:2000 --rays 2000 --shapes 2000 --reps 1 --quiet \
    --json "$tmp/bench.json" &&
    cp "$tmp/out" "$tmp/bench.md" &&
    check "... prints the build table" grep -q '^| engine | build s | Mtris/s | open ms | bytes/tri |' "$tmp/bench.md" &&
    check "... prints the speed table" \
        grep -q '^| rays | query | engine | variant | threads | MRays/s | MRays/s/thread | nodes/ray | tris/ray |' "$tmp/bench.md" &&
    check "... prints the agreement table" grep -q '^| rays | engine | variant | same triangle | both miss |' "$tmp/bench.md" &&
    check "... a row per ray set, query and traversal, and cbvh sorted again at 2 threads" \
        test "$(grep -c '^| \(incoherent\|coherent\|shadow\|short\) | \(closest\|any\) | cbvh | ' "$tmp/bench.md")" -eq 56 &&
    check "... prints the shape table" \
        grep -q '^| shape | query | engine | threads | µs/query | queries/s | queries/s/thread |' "$tmp/bench.md" &&
    check "... a cbvh row per shape set and thread count" \
        test "$(grep -c '^| \(sphere\|capsule\|box\|oriented box\) | \(sweep\|overlap\|first-hit\) | cbvh | [12] | ' "$tmp/bench.md")" -eq 20 &&
    check "... progress stays off stdout" test "$(grep -c '%' "$tmp/bench.md")" -eq 0

# tinybvh is a peer only when configure was given it; without it (or on a CPU without AVX2 and FMA, which its
# kernels were compiled for) the bench says so once and runs on.
tinybvh_rows=$(grep -c '^| [a-z]* | \(closest\|any\) | tinybvh-bvh[48] | single | ' "$tmp/bench.md")
if [ "${CBVH_TINYBVH:-no}" = yes ] && grep -q '^tinybvh was built for AVX2 and FMA, which this CPU lacks' "$tmp/bench.md"; then
    check "bench: without AVX2 and FMA, no tinybvh rows" test "$tinybvh_rows" -eq 0
    skip "bench: tinybvh rows: this CPU lacks AVX2 or FMA"
elif [ "${CBVH_TINYBVH:-no}" = yes ]; then
    # 4 ray sets x 2 queries: BVH8_CPU and BVH4_CPU at 1 thread, BVH8_CPU (the main variant) again at 2
    check "bench: tinybvh BVH8_CPU and BVH4_CPU rows beside the others" test "$tinybvh_rows" -eq 24
    check "... and no note that tinybvh is missing" test "$(grep -c '^tinybvh was' "$tmp/bench.md")" -eq 0
else
    check "bench: says once that tinybvh was not given at configure time" \
        test "$(grep -c '^tinybvh was not given at configure time (--with-tinybvh=DIR): no tinybvh figures' "$tmp/bench.md")" -eq 1
    check "... and runs on without tinybvh rows" test "$tinybvh_rows" -eq 0
    skip "bench: tinybvh rows and agreement: the build has no tinybvh (configure --with-tinybvh=DIR, DIR holding tiny_bvh.h)"
fi

# Jolt likewise: a ray method and a shape engine when configure was given it and the CPU runs its build.
jolt_rows=$(grep -c '^| [a-z]* | \(closest\|any\) | jolt | meshshape | ' "$tmp/bench.md")
jolt_shape_rows=$(grep -c '^| \(sphere\|capsule\|box\|oriented box\) | \(sweep\|overlap\|first-hit\) | jolt | [12] | ' "$tmp/bench.md")
if [ "${CBVH_JOLT:-no}" = yes ] && grep -q '^Jolt was built for AVX2 and FMA, which this CPU lacks' "$tmp/bench.md"; then
    check "bench: without AVX2 and FMA, no Jolt rows" test "$jolt_rows" -eq 0 -a "$jolt_shape_rows" -eq 0
    skip "bench: Jolt rows: this CPU lacks AVX2 or FMA"
elif [ "${CBVH_JOLT:-no}" = yes ]; then
    # 4 ray sets x 2 queries and 10 shape sets, each at 1 and 2 threads
    check "bench: Jolt rows on every ray set and shape set" test "$jolt_rows" -eq 16 -a "$jolt_shape_rows" -eq 20
    check "... says its tolerances are absolute" grep -q "^Jolt's tolerances are absolute" "$tmp/bench.md"
    check "... and no note that Jolt is missing" test "$(grep -c '^Jolt Physics was not given\|^Jolt was built' "$tmp/bench.md")" -eq 0
else
    check "bench: says once that Jolt was not given at configure time" \
        test "$(grep -c '^Jolt Physics was not given at configure time (--with-jolt=PREFIX): no Jolt figures' "$tmp/bench.md")" -eq 1
    check "... and runs on without Jolt rows" test "$jolt_rows" -eq 0 -a "$jolt_shape_rows" -eq 0
    skip "bench: Jolt rows and agreement: the build has no Jolt (configure --with-jolt=PREFIX, README.md)"
fi

# --baseline: another build of libcbvh, loaded at run time, timed on the same file and rays. The build's own
# shared library (libtool keeps it in lib/.libs) stands in for another build: same answers, ray by ray.
printf 'not a library\n' >"$tmp/not_a_library.so"
if [ "${CBVH_DLOPEN:-no}" = yes ]; then
    run 2 "bench --baseline of a missing library" "$CBVH" bench --gen sphere:200 --rays 100 --shapes 0 --reps 1 \
        --quiet --no-peers --baseline "$tmp/missing.so" &&
        check "... names the library" grep -q 'baseline .*missing.so: cannot load it' "$tmp/err" &&
        check "... and prints no table" test ! -s "$tmp/out"
    run 2 "bench --baseline of a file that is not a library" "$CBVH" bench --gen sphere:200 --rays 100 \
        --shapes 0 --reps 1 --quiet --no-peers --baseline "$tmp/not_a_library.so" &&
        check "... names the file" grep -q 'not_a_library.so: cannot load it' "$tmp/err"
    shared_lib="$(dirname "$(dirname "$CBVH")")/lib/.libs/libcbvh.so"
    if [ -f "$shared_lib" ]; then
        run 0 "bench --baseline (this build's shared library)" "$CBVH" bench --gen sphere:2000 --rays 2000 \
            --shapes 0 --reps 1 --threads 1,2 --quiet --no-peers --baseline "$shared_lib" &&
            check "... a baseline row for sorted and stream per ray set and query, sorted again at 2 threads" \
                test "$(grep -c '^| [a-z]* | \(closest\|any\) | baseline | \(sorted\|stream\) | ' "$tmp/out")" -eq 24 &&
            check "... which agree with cbvh ray by ray (every agreement row: no disagreement)" \
                test "$(grep -c '^| [a-z]* | baseline | \(sorted\|stream\) | [0-9]* | [0-9]* | 0 | 0 | 0 | 2000 |' "$tmp/out")" -eq 8
    else
        skip "bench --baseline with a real library: this build has no shared libcbvh (configure --disable-shared)"
    fi
else
    run 2 "bench --baseline without dlopen" "$CBVH" bench --gen sphere:200 --rays 100 --shapes 0 --reps 1 \
        --quiet --no-peers --baseline "$tmp/not_a_library.so" &&
        check "... says the build cannot load libraries" grep -q 'needs dlopen' "$tmp/err"
fi

if [ "$has_python" = 1 ] && [ -f "$tmp/bench.json" ]; then
    check "bench --json is valid JSON" python3 -m json.tool "$tmp/bench.json" /dev/null
    # Every traversal and every peer agrees with cbvh sorted on a closed sphere, ray by ray.
    check "bench: cbvh traversals and peers agree ray by ray" python3 - "$tmp/bench.json" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
assert d["triangles"] >= 2000 and d["rays"] == 2000, d
engines = {b["engine"] for b in d["builds"]}
assert "cbvh" in engines
rows = d["agreement"]
assert len(rows) >= 3 * 4, len(rows)
for r in rows:
    total = r["same_triangle"] + r["both_miss"] + r["t_close_other_triangle"] + r["disagree"]
    assert total == r["closest_rays_compared"] == 2000 and r["any_rays_compared"] == 2000, r
    assert r["disagree"] == 0 and r["any_disagree"] == 0, r
    assert r["same_triangle"] > 0 and r["both_miss"] > 0, r
    # disagreements decided against the reference: at most 200 per set and query, each for one side
    for q, disagree in (("closest", r["disagree"]), ("any", r["any_disagree"])):
        sides = sum(r[q + "_reference_sides_" + k] for k in ("cbvh", "this", "both", "neither"))
        assert sides == r[q + "_disagreements_checked"] <= min(disagree, 200), r
assert "cbvh expanded" in engines, engines
assert any(r["engine"] == "cbvh" and r["variant"] == "expanded" for r in rows), rows
for e in engines - {"cbvh", "cbvh expanded"}:
    assert any(r["engine"] == e for r in rows), e
# tinybvh, when configure was given it and the CPU runs it: both layouts on every ray set (their agreement is
# checked above with every peer's), the blocks its queries read a part of what it keeps
tinybvh = {b["engine"]: b for b in d["builds"] if b["engine"].startswith("tinybvh")}
if tinybvh:
    assert set(tinybvh) == {"tinybvh-bvh8", "tinybvh-bvh4"}, tinybvh
    for e, b in tinybvh.items():
        assert 0 < b["traversed_bytes"] <= b["structure_bytes"] == b["bytes"], b
        assert len([r for r in rows if r["engine"] == e]) == 4, e
        assert len([r for r in d["results"] if r["engine"] == e and r["threads"] == 1]) == 8, e
for r in d["results"]:
    assert r["mrays_per_s"] > 0 and r["threads"] in (1, 2), r
    if r["engine"] == "cbvh":
        assert r["nodes_per_ray"] >= 1 and r["triangles_per_ray"] > 0, r
assert d["threads"] == [1, 2] and d["shapes"] == 2000, d
shapes = d["shape_results"]
kinds = {(r["shape"], r["query"]) for r in shapes}
assert kinds == {(k, q) for k in ("sphere", "capsule", "box") for q in ("sweep", "overlap", "first-hit")} | \
    {("oriented box", "sweep")}, kinds
for r in shapes:
    assert r["us_per_query"] > 0 and r["queries_per_s"] > 0 and r["threads"] in (1, 2), r
    assert r["queries_timed"] == 2000 or r["engine"] != "cbvh", r
    # the generated shapes touch the closed sphere now and then, and not always
    found = r["triangles_per_query"] if r["query"] == "overlap" else r["hits_per_query"]
    assert 0.05 < found < (50 if r["query"] == "overlap" else 1), r
# Bullet and Jolt, when configure found them, answer every shape set; mostly as cbvh does (Bullet's casts stop
# short of contact and its box tests differ at touching triangles: counted, not required to be zero)
peers = {r["engine"] for r in shapes} - {"cbvh"}
agree = d["shape_agreement"]
assert {r["engine"] for r in agree} == peers, agree
# every set, but Bullet answers no first-hit overlap (it cannot stop at the first triangle)
for p in peers:
    assert len([r for r in agree if r["engine"] == p]) == (7 if p == "bullet" else 10), (p, agree)
# cbvh's first hits, on the same queries as its overlaps, touch at most one triangle each, so no more than those
for k in ("sphere", "capsule", "box"):
    first = [r for r in shapes if (r["shape"], r["query"], r["engine"]) == (k, "first-hit", "cbvh")]
    every = [r for r in shapes if (r["shape"], r["query"], r["engine"]) == (k, "overlap", "cbvh")]
    assert first and every and 0 < first[0]["hits_per_query"] <= min(1, every[0]["triangles_per_query"]), (first, every)
for r in agree:
    if r["query"] == "sweep":
        same = r["same_triangle"] + r["both_miss"] + r["t_close_other_triangle"]
        assert r["cbvh_start_touching"] >= 0 and r["t_distance_max_over_diagonal"] >= 0, r
    else:
        same = r["same_set"] + r["both_empty"]
        assert r["cbvh_triangles"] > 0 and r["this_triangles"] > 0, r
    assert same + r["disagree"] == r["queries_compared"] > 0, r
    assert same >= 0.8 * r["queries_compared"], r
    # disagreements decided against the reference: some, at most 200, each for one side
    sides = sum(r["reference_sides_" + k] for k in ("cbvh", "this", "both", "neither"))
    assert sides == r["disagreements_checked"] <= min(r["disagree"], 200), r
    assert r["disagreements_checked"] > 0 or r["disagree"] == 0, r
# Jolt keeps its own compressed copy of the triangles (no shared mesh arrays) and drops none of the sphere's
jolt = [b for b in d["builds"] if b["engine"] == "jolt"]
if jolt:
    assert jolt[0]["bytes"] == jolt[0]["structure_bytes"] > jolt[0]["id_bytes"] > 0, jolt
    assert "dropped_triangles" not in jolt[0], jolt
    assert "jolt" in peers, peers
print("peers:", sorted(engines - {"cbvh"}), "shape peers:", sorted(peers))
EOF
else
    skip "bench JSON checks: python3 not found"
fi

run 0 "bench --threads 2 --no-peers --cpu-time" "$CBVH" bench --gen terrain:3000 --rays 3000 --shapes 500 --reps 2 --threads 2 \
    --no-peers --cpu-time &&
    check "... says it used CPU time" grep -q "CPU time" "$tmp/out" &&
    check "... measures cbvh only" test "$(grep -c '| embree\|| bullet\|| tinybvh\|| jolt' "$tmp/out")" -eq 0 &&
    check "... all traversals agree" sh -c "grep '^| [a-z]* | cbvh | ' '$tmp/out' | awk -F'|' '\$8 != 0 || \$9 != 0 { bad = 1 } END { exit bad }'"

if run 0 "cook a file to bench" "$CBVH" cook gen:sphere:1000 "$tmp/sphere.cbvh"; then
    run 0 "bench of a cooked .cbvh file" "$CBVH" bench "$tmp/sphere.cbvh" --rays 1000 --shapes 0 --threads 1 --reps 1 --quiet &&
        check "... no shape rows with --shapes 0" test "$(grep -c '| sweep \|| overlap ' "$tmp/out")" -eq 0 &&
        check "... has no cook time" grep -q '^| cbvh | - | - |' "$tmp/out"
fi

# ---- report -----------------------------------------------------------------------------------

run 0 "report --gen sphere:2000" "$CBVH" report --gen sphere:2000 --rays 2000 --sample 500 --reps 1 --quiet \
    --json "$tmp/report.json" --svg "$tmp/report.svg" --html "$tmp/report.html" &&
    cp "$tmp/out" "$tmp/report.md" &&
    check "... prints the table with error and run-time columns" \
        grep -q '^| mesh | configuration | bytes/tri | open ms | closest MRays/s | any MRays/s | nodes/ray | tris/ray | extra nodes/ray | extra tris/ray | box inflation mean | box inflation worst | flips | wrong tri | t err max | t err RMS | vertex err | leaked rays |' "$tmp/report.md" &&
    check "... one row per configuration" test "$(grep -c '^| sphere:2000 | \(binary\|wide4\) layout, ' "$tmp/report.md")" -eq 18 &&
    check "... no ray leaks through the closed sphere" \
        test "$(grep '^| sphere:2000 |' "$tmp/report.md" | grep -vc '| 0 / [0-9]* |$')" -eq 0 &&
    check "... recommends an exact configuration" grep -q '^\*\*sphere:2000\.\*\* Recommended: ' "$tmp/report.md"
run 2 "report --html into a missing folder" "$CBVH" report --gen cube --rays 100 --sample 10 --reps 1 --quiet \
    --html "$tmp/missing/report.html" && check "... names the file" grep -q 'missing/report.html' "$tmp/err"

if [ "$has_python" = 1 ] && [ -f "$tmp/report.json" ]; then
    check "report --json is valid JSON" python3 -m json.tool "$tmp/report.json" /dev/null
    check "report: exact answers with float vertices, bounded error with quantized ones" python3 - "$tmp/report.json" <<'EOF'
import json, os, sys
rows = json.load(open(sys.argv[1]))["rows"]
assert len(rows) == 18, len(rows)
# wide4 (the default): leaf 1, 2, 4; at leaf 8 the float-box reference and five variants (four traversals,
# expanded triangles), quantized vertices, zlib; binary: leaf 8, and at leaf 16 its six variants (the
# stackless walk is binary's only)
assert sum(r["layout"] == "wide4 layout" for r in rows) == 11, rows
assert sum(r["layout"] == "binary layout" for r in rows) == 7, rows
assert sorted(r["traversal"] for r in rows if r["layout"] == "binary layout" and r["leaf_size"] == 16) == \
    ["distance", "expanded", "sorted", "stackless", "stream", "unsorted"], rows
raw = [r for r in rows if r["layout"] == "wide4 layout" and r["leaf_size"] == 8 and r["vertices"] == "float" and r["boxes"] == "q16" and r["zlib_level"] == 0]
packed = [r for r in rows if r["zlib_level"] > 0]
assert len(raw) == 5 and len(packed) == 1, (raw, packed)
# the expanded triangles' copy counts in their bytes: 36 a triangle more than the file (none is made
# by a build without SIMD, CBVH_SIMD=no, whose scalar test reads the file as it is)
expanded = [r for r in raw if r["traversal"] == "expanded"][0]
sorted_raw = [r for r in raw if r["traversal"] == "sorted"][0]
copy = 36 if os.environ.get("CBVH_SIMD", "yes") != "no" else 0
gap = expanded["bytes_per_triangle"] - sorted_raw["bytes_per_triangle"]
assert abs(gap - copy) < 0.5, (expanded, sorted_raw)
assert sum(r["default"] for r in rows) == 1 and [r for r in rows if r["default"]][0]["layout"] == "wide4 layout", rows
assert packed[0]["bytes_per_triangle"] < raw[0]["bytes_per_triangle"], (packed, raw)
for r in rows:
    assert r["leaked_rays"] == 0 and r["leak_test_rays"] > 0, r
    assert r["closest_mrays_per_s"] > 0 and r["any_mrays_per_s"] > 0, r
    if r["vertices"] == "float":
        assert r["hit_flips"] == 0 and r["wrong_triangle"] == 0, r
        assert r["t_error_max"] < 1e-5 and r["vertex_error"] == 0, r
    else:
        assert 0 < r["vertex_error"] < 1e-4, r
    if r["boxes"] == "float":
        assert r["extra_nodes_per_ray"] == 0 and r["box_inflation_worst"] == 0, r
    elif r["vertices"] == "float":
        assert r["box_inflation_worst"] > 0, r
    if r["traversal"] == "sorted" and r["boxes"] == "q16":
        assert r["extra_nodes_per_ray"] >= 0, r
EOF
    check "report --svg is a well-formed SVG: six panels, a marker per configuration in each, a legend" \
        python3 - "$tmp/report.svg" <<'EOF'
import sys
import xml.etree.ElementTree as ET
root = ET.parse(sys.argv[1]).getroot()
ns = "{http://www.w3.org/2000/svg}"
assert root.tag == ns + "svg", root.tag
panels = [g for g in root.iter(ns + "g") if g.get("class") == "panel"]
assert len(panels) == 6, len(panels)
for k, p in enumerate(panels): # the last is size against open time: the float-box reference is no file
    points = [t for t in p.iter(ns + "title")]
    assert len(points) == (18 if k < 5 else 17), (k, len(points))
    assert sum(1 for x in p.iter(ns + "path") if x.get("class") == "front") == 1
texts = [t.text or "" for t in root.iter(ns + "text")]
assert any("ns per ray" in t for t in texts), texts[:5]
for legend in ("default: wide4 layout, q16 boxes, float vertices, leaf 8, sorted, raw sections", "layout", "box precision",
               "vertex precision", "leaf size", "traversal", "sections"):
    assert legend in texts, legend
EOF
    check "report --html: self-contained, six plots with a focusable point per configuration, advice, table" \
        python3 - "$tmp/report.html" <<'EOF'
import re, sys
from html.parser import HTMLParser
page = open(sys.argv[1], encoding="utf-8").read()
assert not re.search(r"""(src|href)\s*=|url\(|@import|<link|<script""", page), "refers to something outside the page"
class Page(HTMLParser):
    def __init__(self):
        super().__init__()
        self.plots, self.stack, self.advice, self.rows = [], [], 0, 0
    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        cls = a.get("class", "")
        if tag == "svg" and cls == "plot":
            self.plots.append({"points": 0, "front": 0, "label": a.get("aria-label", "")})
        if self.plots and tag == "g" and cls == "pt":
            assert a.get("tabindex") == "0", a
            self.plots[-1]["points"] += 1
        if self.plots and tag == "path" and cls == "front":
            self.plots[-1]["front"] += 1
        if tag == "p" and cls == "advice":
            self.advice += 1
        if tag == "tr":
            self.rows += 1
p = Page()
p.feed(page)
plots = [x for x in p.plots if not x["label"].startswith("legend")]
assert len(plots) == 6, plots
for k, x in enumerate(plots):
    assert x["points"] == (18 if k < 5 else 17) and x["front"] == 1, (k, x)
assert p.advice == 1 and p.rows == 1 + 18, (p.advice, p.rows)
assert "Recommended: " in page
EOF
else
    skip "report JSON, SVG and HTML checks: python3 not found"
fi

run 0 "report --out DIR" "$CBVH" report --gen cube --rays 500 --sample 100 --reps 1 --quiet --out "$tmp/out-dir" &&
    check "... writes report.md, report.json, report.svg, report.html and the cooked files" \
        test -s "$tmp/out-dir/report.md" -a -s "$tmp/out-dir/report.json" -a -s "$tmp/out-dir/report.svg" -a -s "$tmp/out-dir/report.html" \
        -a -s "$tmp/out-dir/cube-wide4-leaf8.cbvh" -a -s "$tmp/out-dir/cube-wide4-leaf8-qverts.cbvh" -a -s "$tmp/out-dir/cube-wide4-leaf8-zlib.cbvh" -a -s "$tmp/out-dir/cube-binary-leaf16.cbvh"

finish
