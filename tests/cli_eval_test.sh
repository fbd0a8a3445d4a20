#!/usr/bin/env bash
# End-to-end checks of `dsreg eval` and `dsreg convergence`: outputs, JSON keys, CSV columns,
# exit codes, error messages, known answers on hand-written meshes (a cube and an octahedron
# against the unit sphere), and that a failed run leaves no output behind.
OUTPUTS='out*'
source "$(dirname "$0")/cli_harness.sh"

# --- eval ------------------------------------------------------------------------------------
"$DSREG" regularize --shape sphere1 --h 0.1 --normals exact -o "$work/s.obj" --input-mesh "$work/digital.off" -q
check "regularize for eval" test -s "$work/s.obj"

table=$("$DSREG" eval "$work/s.obj" --shape sphere1 --h 0.1)
check "eval exits 0" test $? -eq 0
check "table has vertex distance" grep -q "vertex distance / h" <<<"$table"
check "table has normal angle" grep -q "normal angle" <<<"$table"
check "table has voxel classification" grep -q "voxel centres correct" <<<"$table"

json=$("$DSREG" eval "$work/s.obj" --shape sphere1 --h 0.1 --json)
for key in vertex_distance vertex_distance_h normal_angle_deg p95 relative_volume_error voxel_classification \
    triangle_min_angle_deg '"l2"' '"linf"' '"mean"' '"share"' '"correct"' '"total"' '"min"'; do
    check "json has $key" grep -q "$key" <<<"$json"
done
check "json is one object" test "$(head -c 1 <<<"$json")" = "{"
json_no_h=$("$DSREG" eval "$work/s.obj" --shape sphere1 --json)
check "no units of h without --h" test -z "$(grep vertex_distance_h <<<"$json_no_h")"
check "voxel classification uses the default h" grep -q '"voxel_classification"' <<<"$json_no_h"

# The digital surface classifies every voxel centre of its own digitization correctly, and all
# its vertices are within sqrt(3)/2 h of the sphere.
json_digital=$("$DSREG" eval "$work/digital.off" --shape sphere1 --h 0.1 --json)
check "digital surface: 100% of voxels" grep -q '"share": 1.0' <<<"$json_digital"
linf_h=$(grep -A4 '"vertex_distance_h"' <<<"$json_digital" | grep '"linf"' | grep -o '[0-9.e-]*,\?$' | tr -d ,)
check "digital surface within sqrt(3)/2 h" awk -v x="$linf_h" 'BEGIN { exit !(x > 0 && x <= 0.8661) }'

# Other formats, including a mesh written as triangles.
"$DSREG" regularize --shape goursat --h 0.5 -o "$work/g.stl" -q
"$DSREG" regularize --shape goursat --h 0.5 -o "$work/g.ply" -q
stl_json=$("$DSREG" eval "$work/g.stl" --shape goursat --h 0.5 --json)
check "eval reads STL (triangles)" grep -q '"triangle_min_angle_deg"' <<<"$stl_json"
ply_json=$("$DSREG" eval "$work/g.ply" --shape goursat --h 0.5 --json)
check "eval reads PLY (quads)" grep -q '"normal_angle_deg"' <<<"$ply_json"

# A tilted plane: box walls are left out of the distance statistics.
"$DSREG" regularize --shape "0.408248290463863*x+0.577350269189626*y+0.707106781186548*z-0.01" --box 1 --h 0.1 \
    --gamma 0 --alpha 1e-7 -o "$work/plane.obj" -q
plane=$("$DSREG" eval "$work/plane.obj" --shape plane --h 0.1)
check "plane: walls left out" grep -q "clipped box face left out" <<<"$plane"

# Meshes with known answers, written by hand.
json_field() {  # json_field JSON OBJECT FIELD: the number FIELD of the top-level object OBJECT
    awk -v obj="\"$2\": {" -v field="\"$3\":" '
        index($0, obj) { inside = 1; next }
        inside && /}/ { inside = 0 }
        inside && index($0, field) { sub(/.*: */, ""); sub(/,$/, ""); print; exit }' <<<"$1"
}
json_top() {  # json_top JSON KEY: a top-level number
    awk -v key="  \"$2\":" 'index($0, key) == 1 { sub(/.*: */, ""); sub(/,$/, ""); print; exit }' <<<"$1"
}
near() {  # near X Y TOLERANCE
    awk -v x="$1" -v y="$2" -v t="$3" 'BEGIN { d = x - y; if (d < 0) d = -d; exit !(x != "" && d <= t) }'
}
# The cube [-1,1]^3 (6 quads) against the unit sphere: every vertex is sqrt(3) - 1 away, every face
# centroid is on an axis (angle 0), the volume is 8 against 4/3 pi, and at h = 0.3 the voxel centres
# (0.3 i, 0.3 j, 0.3 k), |i|,|j|,|k| <= 5, inside the cube but outside the sphere are 172 of 11^3.
printf 'v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n' >"$work/cube.obj"
printf 'f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n' >>"$work/cube.obj"
cube=$("$DSREG" eval "$work/cube.obj" --shape sphere1 --h 0.3 --json)
check "cube: 8 vertices, 6 faces" test "$(json_field "$cube" vertices evaluated)$(json_field "$cube" faces evaluated)" = 86
check "cube: vertex distance Linf sqrt(3)-1" near "$(json_field "$cube" vertex_distance linf)" 0.7320508075688772 1e-12
check "cube: vertex distance mean sqrt(3)-1" near "$(json_field "$cube" vertex_distance mean)" 0.7320508075688772 1e-12
check "cube: in units of h" near "$(json_field "$cube" vertex_distance_h linf)" 2.440169358562924 1e-9
check "cube: normal angle 0" near "$(json_field "$cube" normal_angle_deg linf)" 0 1e-9
check "cube: volume 8" near "$(json_top "$cube" mesh_volume)" 8 1e-12
check "cube: relative volume error 6/pi - 1" near "$(json_top "$cube" relative_volume_error)" 0.909859317102744 1e-6
check "cube: 11^3 voxels" test "$(json_field "$cube" voxel_classification total)" = 1331
check "cube: 172 voxels wrong" test "$(json_field "$cube" voxel_classification correct)" = 1159
check "cube: 12 right triangles" test "$(json_field "$cube" triangle_min_angle_deg triangles)" = 12
check "cube: 45 degrees" near "$(json_field "$cube" triangle_min_angle_deg min)" 45 1e-9
# The regular octahedron |x|+|y|+|z| = 1, an exact (inscribed) sphere triangulation: vertices on the
# sphere, face normals (+-1,+-1,+-1)/sqrt(3) radial at the centroids, volume 4/3, equilateral.
printf 'v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n' >"$work/octahedron.obj"
printf 'f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n' >>"$work/octahedron.obj"
octahedron=$("$DSREG" eval "$work/octahedron.obj" --shape sphere1 --h 0.3 --json)
check "octahedron: vertices on the sphere" near "$(json_field "$octahedron" vertex_distance linf)" 0 1e-12
check "octahedron: normals radial" near "$(json_field "$octahedron" normal_angle_deg linf)" 0 1e-6
check "octahedron: relative volume error 1/pi - 1" near "$(json_top "$octahedron" relative_volume_error)" -0.681690113816209 1e-6
check "octahedron: equilateral" near "$(json_field "$octahedron" triangle_min_angle_deg min)" 60 1e-9
# The same octahedron shifted by 0.25 along x: (1.25,0,0) and (-0.75,0,0) are 0.25 away, the
# four others sqrt(1.0625) - 1.
printf 'v 1.25 0 0\nv -0.75 0 0\nv 0.25 1 0\nv 0.25 -1 0\nv 0.25 0 1\nv 0.25 0 -1\n' >"$work/shifted.obj"
grep '^f' "$work/octahedron.obj" >>"$work/shifted.obj"
shifted=$("$DSREG" eval "$work/shifted.obj" --shape sphere1 --json)
check "shifted octahedron: Linf 0.25" near "$(json_field "$shifted" vertex_distance linf)" 0.25 1e-12
check "shifted octahedron: mean" near "$(json_field "$shifted" vertex_distance mean)" \
    "$(awk 'BEGIN { printf "%.15f", (2 * 0.25 + 4 * (sqrt(1.0625) - 1)) / 6 }')" 1e-12

# --- digitize ------------------------------------------------------------------------------
# The .vol file holds the very voxels regularize digitizes: the same digital surface from both.
grid=$("$DSREG" digitize --shape goursat --h 0.5 -o "$work/g.vol")
check "digitize prints the grid" grep -q "^dims [0-9]*,[0-9]*,[0-9]* spacing 0.5,0.5,0.5 origin " <<<"$grid"
"$DSREG" regularize --shape goursat --h 0.5 -o "$work/g-shape.obj" --report "$work/g-shape.json" -q
"$DSREG" regularize "$work/g.vol" -o "$work/g-file.obj" --report "$work/g-file.json" -q
surfels() { grep -o '"surfels": [0-9]*' "$1"; }
check "digitize: same surfels as --shape" test "$(surfels "$work/g-shape.json")" = "$(surfels "$work/g-file.json")"
"$DSREG" regularize "$work/g.vol" -o "$work/g-file.obj" --input-mesh "$work/g-digital.obj" -q
vjson=$("$DSREG" eval "$work/g-digital.obj" --volume "$work/g.vol" --json)
check "eval --volume: the digital surface gets every voxel" test "$(grep -c 'share": 1.0' <<<"$vjson")" -eq 3
vtable=$("$DSREG" eval "$work/g-file.obj" --volume "$work/g.vol")
check "eval --volume table: next to the surface" grep -q "next to the surface" <<<"$vtable"
json_g=$("$DSREG" eval "$work/g-shape.obj" --shape goursat --h 0.5 --json)
check "eval --shape: object and boundary shares" grep -q '"boundary_share"' <<<"$json_g"
"$DSREG" eval "$work/g-file.obj" --shape goursat --h 0.5 --voxel-coordinates --face-errors "$work/g-faces.csv" >/dev/null
check "eval --face-errors: a line per face" test "$(($(wc -l <"$work/g-faces.csv") - 1))" -eq "$(grep -c '^f ' "$work/g-file.obj")"
expect_error "eval --face-errors with --volume" "--face-errors" eval "$work/g-file.obj" --volume "$work/g.vol" --face-errors "$work/x.csv"
check "eval: no CSV after an error" test ! -e "$work/x.csv"
expect_error "eval without truth" "--volume" eval "$work/g-file.obj"
expect_error "eval --volume with --h" "--volume" eval "$work/g-file.obj" --volume "$work/g.vol" --h 0.5
expect_error "eval --min without --volume" "--min" eval "$work/g-file.obj" --shape goursat --min 1
expect_error "eval --volume missing file" "nothere.vol" eval "$work/g-file.obj" --volume "$work/nothere.vol"
expect_error "digitize without --shape" "--shape" digitize --h 0.5 -o "$work/out.vol"
expect_error "digitize to a mesh" ".vol" digitize --shape goursat --h 0.5 -o "$work/out.obj"
expect_error "digitize unknown shape" "blob" digitize --shape blob -o "$work/out.vol"

# --- convergence -----------------------------------------------------------------------------
summary=$("$DSREG" convergence --shape sphere1 --h 0.2:0.1:3 --out "$work/conv/nested" 2>"$work/progress.txt")
check "convergence exits 0" test $? -eq 0
check "creates the nested folder" test -d "$work/conv/nested"
csv="$work/conv/nested/convergence.csv"
check "csv written" test -s "$csv"
header=$(head -n 1 "$csv")
for column in h faces normal_l2 normal_linf p_l2 p_linf pstar_l2 pstar_linf; do
    check "csv has column $column" grep -q "\(^\|,\)$column\(,\|$\)" <<<"$header"
done
check "csv has one row per h" test "$(wc -l <"$csv")" -eq 4
check "first row is the largest h" test "$(sed -n 2p "$csv" | cut -d, -f1)" = "0.2"
check "svg written" grep -q "^<svg" "$work/conv/nested/convergence.svg"
check "svg closed" grep -q "</svg>" "$work/conv/nested/convergence.svg"
check "summary has slopes" grep -q "slope" <<<"$summary"
check "summary compares p* and p" grep -q "p\* closer to the surface than p" <<<"$summary"
check "progress per h on stderr" test "$(grep -c '^convergence: \[' "$work/progress.txt")" -eq 3
"$DSREG" convergence --shape plane --h 0.2:0.1:2 --out "$work/conv-plane" -q >/dev/null
check "plane convergence" test "$(wc -l <"$work/conv-plane/convergence.csv")" -eq 3
"$DSREG" convergence --shape sphere1 --h 0.2:0.15:2 --normals ii --radius-k 2 --alpha-k 1e-4 --gamma 0.001 \
    --out "$work/conv-ii" -q >/dev/null
check "ii convergence" grep -q "^0.2," "$work/conv-ii/convergence.csv"
"$DSREG" convergence --shape sphere1 --h 0.2:0.15:2 --normals ii --radius-k 2 --alpha-k 1e-4 --gamma 0.001 \
    --ii-kernel ball --out "$work/conv-ball" -q >/dev/null
check "ii kernel ball runs" grep -q "^0.2," "$work/conv-ball/convergence.csv"
check "ii kernel changes the input field" test "$(sed -n 2p "$work/conv-ii/convergence.csv")" != "$(sed -n 2p "$work/conv-ball/convergence.csv")"
"$DSREG" convergence --shape sphere1 --h 0.2:0.15:2 --normals ii --radius-k 2 --alpha-k 1e-4 --gamma 0.001 \
    --ii-extrapolate --out "$work/conv-ext" -q >/dev/null
check "ii extrapolated runs" grep -q "^0.2," "$work/conv-ext/convergence.csv"
check "extrapolation changes the input field" test "$(sed -n 2p "$work/conv-ii/convergence.csv")" != "$(sed -n 2p "$work/conv-ext/convergence.csv")"

# --- errors: message names the culprit, non-zero exit, nothing written -------------------------
expect_error "missing mesh" "nothing.obj" eval "$work/nothing.obj" --shape sphere1
printf 'v 0 0 0\nf 1 2 3\n' >"$work/broken.obj"
expect_error "malformed mesh" "broken.obj" eval "$work/broken.obj" --shape sphere1
expect_error "eval unknown shape" "blob" eval "$work/s.obj" --shape blob
expect_error "eval negative h" "--h" eval "$work/s.obj" --shape sphere1 --h -0.1
expect_error "range MAX < MIN" "MAX" convergence --shape sphere1 --h 0.1:0.2:3 --out "$work/out"
expect_error "range without COUNT" "MAX:MIN:COUNT" convergence --shape sphere1 --h 0.2:0.1 --out "$work/out"
expect_error "range not numbers" "not a number" convergence --shape sphere1 --h a:0.1:3 --out "$work/out"
expect_error "range COUNT 1" "COUNT" convergence --shape sphere1 --h 0.2:0.1:1 --out "$work/out"
expect_error "convergence unknown shape" "blob" convergence --shape blob --h 0.2:0.1:2 --out "$work/out"
expect_error "radius k zero" "radius-k" convergence --shape sphere1 --h 0.2:0.1:2 --normals ii --radius-k 0 --out "$work/out"
expect_error "unknown ii kernel" "ii-kernel" convergence --shape sphere1 --h 0.2:0.1:2 --normals ii --ii-kernel gauss --out "$work/out"
expect_error "alpha k zero" "alpha" convergence --shape sphere1 --h 0.2:0.1:2 --alpha-k 0 --out "$work/out"
expect_error "failure during the run" "region" convergence --shape plane --h 0.2:0.1:2 --wall-margin 5 --out "$work/out"
touch "$work/file"
expect_error "out is a file" "not a folder" convergence --shape sphere1 --h 0.2:0.1:2 --out "$work/file"

# A failed run does not touch existing results.
mkdir -p "$work/keep" && echo precious >"$work/keep/convergence.csv"
"$DSREG" convergence --shape plane --h 0.2:0.1:2 --wall-margin 5 --out "$work/keep" -q >/dev/null 2>&1
check "existing csv kept on failure" grep -q precious "$work/keep/convergence.csv"

finish
