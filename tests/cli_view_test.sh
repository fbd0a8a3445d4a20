#!/usr/bin/env bash
# End-to-end checks of `dsreg view` and `regularize --html` without a browser (viewer_browser_test.py
# opens the pages):
# the page holds every mesh given, names out of ASCII, and the errors: a mesh without faces, too
# many faces, a digital surface that does not match, a page that is not .html, a missing folder or
# file; a failed run leaves no page behind and keeps an existing one.
OUTPUTS='page*'
source "$(dirname "$0")/cli_harness.sh"

"$DSREG" regularize --shape goursat --h 0.5 -o "$work/g.ply" --input-mesh "$work/gd.obj" -q
"$DSREG" regularize --shape sphere9 --h 1 -o "$work/s.off" -q

# The page holds the layers (JSON element), three.js, and a buffer element per array.
out=$("$DSREG" view "$work/g.ply" "$work/s.off" --digital "$work/gd.obj" -o "$work/page.html" 2>&1)
check "view exits 0" test $? -eq 0
check "view names its page" grep -q "2 meshes -> $work/page.html" <<<"$out"
data=$(grep -o '<script type="application/json" id="dsreg-page">.*</script>' "$work/page.html")
check "two layers" test "$(grep -o '"name":"[^"]*"' <<<"$data" | grep -c -e '"g.ply"' -e '"s.off"')" -eq 2
check "digital surface paired with the mesh of as many vertices" grep -q '"digital surface","'"$work"'/gd.obj"' <<<"$data"
check "displacement of g.ply" grep -q '"kind":"length"' <<<"$data"
check "three.js inside" grep -q 'REVISION="111"' "$work/page.html"
check "buffers inside" grep -q 'id="dsreg-buffer-0-0"' "$work/page.html"

# regularize --html: the run's page, with the digital surface and the summary.
"$DSREG" regularize --shape goursat --h 0.5 -o "$work/r.ply" --html "$work/page-run.html" -q
check "regularize --html writes the page" test -s "$work/page-run.html"
run=$(grep -o '<script type="application/json" id="dsreg-page">.*</script>' "$work/page-run.html")
check "run page: digital surface" grep -q '"digital":{' <<<"$run"
check "run page: summary" grep -q '\["surfels","[0-9]*"\]' <<<"$run"
check "run page: deviation" grep -q '"deviation":{' <<<"$run"
rm -f "$work/page-run.html"
expect_error "regularize --html not .html" "--html $work/page.png: the page must be an .html file" \
    regularize --shape goursat --h 0.5 -o "$work/page.ply" --html "$work/page.png"
expect_error "regularize --html on the report" "--html $work/page.html: same file as --report" \
    regularize --shape goursat --h 0.5 -o "$work/page.ply" --report "$work/page.html" --html "$work/page.html"

# Names out of ASCII, for the meshes and the page.
cp "$work/g.ply" "$work/géométrie 立方体.ply"
"$DSREG" view "$work/géométrie 立方体.ply" -o "$work/page é.html" -q
check "non-ASCII names: page written" test -s "$work/page é.html"
check "non-ASCII names: name in the page" grep -q '"name":"géométrie 立方体.ply"' "$work/page é.html"
rm -f "$work/page é.html"

# Errors: exit 1, a message naming the problem, no page.
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\n' > "$work/points.obj"
expect_error "mesh without faces" "the mesh has no faces (3 vertices): nothing to show" \
    view "$work/points.obj" -o "$work/page.html"
: > "$work/empty.obj"
expect_error "empty mesh file" "the mesh has no faces (0 vertices)" view "$work/empty.obj" -o "$work/page.html"
expect_error "too many faces" "faces in all, more than a page can show (at most 1000" \
    view "$work/g.ply" --digital "$work/gd.obj" -o "$work/page.html" --max-faces 1000
expect_error "digital surface of no mesh" "vertices, but no mesh given has as many" \
    view "$work/s.off" --digital "$work/gd.obj" -o "$work/page.html"
expect_error "page not .html" "the page must be an .html file (got 'obj')" view "$work/g.ply" -o "$work/page.obj"
expect_error "missing folder" "folder $work/no does not exist" view "$work/g.ply" -o "$work/no/page.html"
expect_error "missing mesh" "$work/none.ply" view "$work/none.ply" -o "$work/page.html"
expect_error "no mesh" "meshes is required" view -o "$work/page.html"

# A failed run keeps an existing page as it was.
echo "old page" > "$work/page.html"
"$DSREG" view "$work/points.obj" -o "$work/page.html" 2>/dev/null
check "failed run keeps the existing page" grep -qx "old page" "$work/page.html"
check "failed run leaves no temporary file" test -z "$(ls -A "$work" | grep '^\.')"
rm -f "$work/page.html"

# A label complex (regularize --multi-label) is coloured by the labels on either side of its faces,
# read from the PLY face properties or the VTK cell data arrays.
python3 -c "
import sys
v = bytearray(6 * 5 * 5)
for k in range(1, 4):
    for j in range(1, 4):
        for i in range(1, 5):
            v[i + 6 * (j + 5 * k)] = 1 if i < 3 else 4
open(sys.argv[1], 'wb').write(v)" "$work/two.raw"
for ext in ply vtk vtp; do
    "$DSREG" regularize "$work/two.raw" --raw-dims 6,5,5 --multi-label --normals trivial -o "$work/two.$ext" -q
    "$DSREG" view "$work/two.$ext" -o "$work/page-labels.html" -q
    labels=$(grep -o '<script type="application/json" id="dsreg-page">.*</script>' "$work/page-labels.html")
    check "view colours a .$ext label complex by its labels" grep -q '"labels":{[^}]*"values":\[0,1,4\]' <<<"$labels"
    check "view lists the .$ext face labels" grep -q 'inner_label per face' <<<"$labels"
done
"$DSREG" view "$work/two-4.ply" -o "$work/page-labels.html" -q
check "one label's surface has no label colours" test -z "$(grep -o '"labels":{' "$work/page-labels.html")"
rm -f "$work/page-labels.html"

finish
