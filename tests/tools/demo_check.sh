#!/usr/bin/env bash
# `make demo` end to end (ctest Demo.ShowsTheEverydayPaths): tools/demo.sh into a scratch folder,
# then the paths the README says it shows — the bunny fitted, rendered and coloured by its measured
# error, exported as a mesh within its bound, a volume converted at its suggested (Otsu) iso
# value — and the pictures, non-empty. Skips (77) without the bunny in ../shared.
set -euo pipefail
q=${1:?quadrix binary}; src=${2:?source folder}
data=${QUADRIX_DATASETS:-$src/../shared/datasets}
[ -f "$data/meshes/bunny.ply" ] || { echo "no $data/meshes/bunny.ply: skipped"; exit 77; }
out=$(mktemp -d); trap 'rm -rf "$out"' EXIT
if ! bash "$src/tools/demo.sh" "$q" "$out" > "$out/log" 2>&1; then cat "$out/log"; echo "demo.sh failed"; exit 1; fi
fail() { echo "demo: $*"; exit 1; }
for f in bunny.png bunny_cpu.png bunny_error.png bunny_mesh.ply quads.png molecule_skin.png marschner_lobb_otsu.png \
         glyphs.png hyperboloid.png; do
  [ -s "$out/$f" ] || fail "no $f"
done
grep -q '"within_bound": true' "$out/bunny_mesh.json" || fail "the bunny's mesh is not within its bound"
grep -q '"mode": "error"' "$out/bunny_error_render.json" || fail "the error picture is not coloured by error"
grep -q '"iso_source": "otsu"' "$out/marschner_lobb_otsu_convert.json" || fail "the volume was not converted at Otsu's iso"
"$q" info "$out/bunny_mesh.ply" | grep -q "triangle mesh" || fail "the exported mesh does not read back"
echo "demo: every path shown"
