#!/bin/sh
# test_materials.sh: `cbvh cook` never loses a material (issue 12's defect 6): one material for every triangle
# is recorded, material names are stored and listed by `cbvh info`, --material-map gives the game's ids (and
# fails on a material it does not name), a side file the asset names but that is missing is warned about.
#
# Environment: as tests/test_tool.sh (CBVH_TOOL). Needs python3 for the JSON checks (skipped without).

name=test_materials.sh
. "$(dirname "$0")/tool_test_lib.sh"

# A cube of two materials and a quad of one, in OBJ with its .mtl. assimp numbers the .mtl's materials after
# its own DefaultMaterial (0): Steel 1, Wood 2.
cat >"$tmp/parts.mtl" <<'MTL'
newmtl Steel
Kd 0.5 0.5 0.5
newmtl Wood
Kd 0.6 0.4 0.2
MTL
cat >"$tmp/quad.obj" <<'OBJ'
mtllib parts.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
usemtl Wood
f 1 2 3
f 1 3 4
OBJ
cat >"$tmp/two.obj" <<'OBJ'
mtllib parts.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
usemtl Steel
f 1 2 3
f 1 3 4
usemtl Wood
f 1 2 6
f 1 6 5
OBJ

# info_json FILE EXPR: evaluates the Python expression EXPR over `cbvh info --json FILE` as d.
info_json() {
    "$CBVH" info --json "$1" >"$tmp/info.json" 2>"$tmp/err" &&
        python3 -c "import json, sys; d = json.load(open(sys.argv[1])); sys.exit(0 if ($2) else 1)" "$tmp/info.json"
}

if [ "$has_python" = 1 ]; then
    run 0 "cook a mesh whose triangles all have material 2" "$CBVH" cook "$tmp/quad.obj" "$tmp/quad.cbvh"
    check "... info: one id, 2, for every triangle (it read back 0 before)" \
        info_json "$tmp/quad.cbvh" 'd["material_ids"] == "uniform" and d["material_uniform_id"] == 2'
    check "... info: the used material's name" \
        info_json "$tmp/quad.cbvh" 'd["material_names"] == [{"id": 2, "name": "Wood"}]'
    "$CBVH" info "$tmp/quad.cbvh" >"$tmp/info.txt"
    check "... info's text says so" grep -q "materials: id 2 for every triangle, 1 names" "$tmp/info.txt"
    check "... and lists the name" grep -q "material 2: Wood" "$tmp/info.txt"
    run 0 "cook two materials" "$CBVH" cook "$tmp/two.obj" "$tmp/two.cbvh"
    check "... per-triangle ids and both names" info_json "$tmp/two.cbvh" \
        'd["material_ids"] == "per-triangle" and d["material_names"] == [{"id": 1, "name": "Steel"}, {"id": 2, "name": "Wood"}]'
    run 0 "cook --no-materials" "$CBVH" cook --no-materials "$tmp/two.obj" "$tmp/none.cbvh"
    check "... stores neither ids nor names" info_json "$tmp/none.cbvh" \
        'd["material_ids"] == "none" and d["material_names"] == []'

    # --material-map: names to the game's ids.
    printf '# physics materials\nSteel\t700\nWood\t4000000000\n' >"$tmp/map.tsv"
    run 0 "cook --material-map" "$CBVH" cook --json --material-map "$tmp/map.tsv" "$tmp/two.obj" "$tmp/mapped.cbvh"
    check "... the file has the map's ids and the names with them" info_json "$tmp/mapped.cbvh" \
        'd["material_names"] == [{"id": 700, "name": "Steel"}, {"id": 4000000000, "name": "Wood"}]'
    check "... --json lists the names with their ids" python3 -c "
import json, sys; d = json.load(open(sys.argv[1]))
assert d['material_names'] == [{'id': 700, 'name': 'Steel'}, {'id': 4000000000, 'name': 'Wood'}], d" "$tmp/out"
    printf 'Wood\t5\n' >"$tmp/partial.tsv"
    run 1 "a material the map does not name fails the cook" "$CBVH" cook --material-map "$tmp/partial.tsv" "$tmp/two.obj" "$tmp/p.cbvh" &&
        check "... the message names the material and the map" grep -q "material 'Steel' (2 triangles) is not in the material map .*partial.tsv" "$tmp/err"
    check "... and nothing is written" test ! -e "$tmp/p.cbvh"
    printf 'Wood\t5\n*\t9\n' >"$tmp/default.tsv"
    run 0 "a '*' line maps every other material" "$CBVH" cook --material-map "$tmp/default.tsv" "$tmp/two.obj" "$tmp/d.cbvh"
    check "... Steel gets 9" info_json "$tmp/d.cbvh" \
        'd["material_names"] == [{"id": 5, "name": "Wood"}, {"id": 9, "name": "Steel"}]'
    printf 'Wood 5\n' >"$tmp/bad.tsv"
    run 2 "a map line without a tab is a usage error" "$CBVH" cook --material-map "$tmp/bad.tsv" "$tmp/two.obj" "$tmp/b.cbvh" &&
        check "... naming the file and line" grep -q "bad.tsv:1: expected NAME<TAB>ID" "$tmp/err"
    printf 'Wood\t5\nWood\t6\n' >"$tmp/twice.tsv"
    run 2 "a name mapped twice is a usage error" "$CBVH" cook --material-map "$tmp/twice.tsv" "$tmp/two.obj" "$tmp/b.cbvh" &&
        check "... naming both lines" grep -q "twice.tsv:2: material 'Wood' is mapped already on line 1" "$tmp/err"
    printf 'Wood\t4294967296\n' >"$tmp/big.tsv"
    run 2 "an id past 32 bits is a usage error" "$CBVH" cook --material-map "$tmp/big.tsv" "$tmp/two.obj" "$tmp/b.cbvh"
    run 2 "a missing map is a usage error" "$CBVH" cook --material-map "$tmp/nope.tsv" "$tmp/two.obj" "$tmp/b.cbvh"
    run 0 "--depfile lists the map" "$CBVH" cook --material-map "$tmp/map.tsv" --depfile "$tmp/two.d" "$tmp/two.obj" "$tmp/m2.cbvh"
    check "... beside the asset and its .mtl" grep -q "two.obj .*parts.mtl .*map.tsv" "$tmp/two.d"
    mkdir "$tmp/batch"
    run 0 "a batch with a map" "$CBVH" cook --material-map "$tmp/default.tsv" --output-dir "$tmp/batch" "$tmp/two.obj" "$tmp/quad.obj"
    check "... cooks both with the map's ids" info_json "$tmp/batch/quad.cbvh" 'd["material_uniform_id"] == 5'

    # A missing .mtl: assimp still imports, with other material numbers; the cook warns.
    mkdir "$tmp/alone"
    cp "$tmp/two.obj" "$tmp/alone/two.obj"
    run 0 "cook an OBJ whose .mtl is missing" "$CBVH" cook --json "$tmp/alone/two.obj" "$tmp/alone.cbvh"
    check "... warns, naming the missing file" grep -q "warning: the asset refers to '.*parts.mtl', which was not found" "$tmp/err"
    check "... --json lists it in missing_files" python3 -c "
import json, sys; d = json.load(open(sys.argv[1])); assert [p for p in d['missing_files'] if p.endswith('parts.mtl')], d" "$tmp/out"
    run 0 "cook with the .mtl present" "$CBVH" cook --json "$tmp/two.obj" "$tmp/with.cbvh"
    check "... warns of nothing" python3 -c "
import json, sys; d = json.load(open(sys.argv[1])); assert d['missing_files'] == [], d" "$tmp/out"
else
    skip "material checks: python3 is needed to read the JSON"
fi

finish
