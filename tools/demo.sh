#!/usr/bin/env bash
# make demo: the pipeline on real and analytic data. Fits the Stanford bunny (SLIM) and renders it
# with the CPU reference and with the GL three-pass SLIM renderer (OSMesa/EGL); converts a quad
# mesh, a molecule's skin surface and CT iso-surfaces into tetrahedron-clipped quadrics and
# ray-casts them with OpenGL (OSMesa/EGL); renders analytic glyph and hyperboloid models. Shows the
# fit coloured by its measured error, a mesh export, and a volume whose iso-value info suggested.
set -euo pipefail
q=${1:?quadrix binary}; out=${2:-out/demo}
here=$(cd "$(dirname "$0")/.." && pwd)
data=${QUADRIX_DATASETS:-$here/../shared/datasets}
mkdir -p "$out"
run() { echo "+ quadrix ${*}"; "$q" "$@"; }

# Real data: ../shared/datasets, or the copies Debian's libcgal-demo ships.
bunny="$data/meshes/bunny.ply"
quads="$data/quads/spot_quadrangulated.obj"
molecule="$data/molecules/4ins.pdb"
skull="$data/volumes/skull_2.9.inr"
lobster="$data/volumes/lobster_120x120x34_uint16.nhdr"
cgal_doc=/usr/share/doc/libcgal-dev
if [ ! -d "$data" ] && [ ! -f $cgal_doc/data.tar.gz ]; then
  # No ../shared: Debian's libcgal-demo ships the real data (bunny, skull, molecules).
  if [ "$(id -u)" -eq 0 ]; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends libcgal-demo >/dev/null ||
      echo "demo: could not install libcgal-demo; analytic models only"
  else
    echo "demo: no datasets; for real data run as root: apt-get install libcgal-demo"
  fi
fi
if [ ! -f "$bunny" ] && [ -f $cgal_doc/data.tar.gz ]; then
  mkdir -p "$out/data"
  tar -xzf $cgal_doc/data.tar.gz -C "$out/data" --wildcards '*bunny*' '*quad*' '*skull_2.9.inr' 2>/dev/null || true
  [ -f $cgal_doc/examples.tar.gz ] &&
    tar -xzf $cgal_doc/examples.tar.gz -C "$out/data" --wildcards '*Skin_surface_3/data/*' 2>/dev/null || true
  bunny=$(find "$out/data" -name 'bunny*.off' -o -name 'bunny*.ply' -o -name 'bunny*.xyz' | head -n1)
  quads=$(find "$out/data" -name 'cube_quad.off' -o -name 'torus_quad.off' | head -n1)
  molecule=$(find "$out/data" -name 'caffeine.cin' -o -name '*.pdb' | head -n1)
  skull=$(find "$out/data" -name 'skull_2.9.inr' | head -n1)
fi

if [ -n "$bunny" ] && [ -f "$bunny" ]; then
  # --allow-exceed: the demo goes on (with the fit's warning) on data that misses the bound.
  run fit "$bunny" -o "$out/bunny.qxm" --max-error 1e-3 --allow-exceed --report "$out/bunny_fit.json"
  run render --backend cpu "$out/bunny.qxm" -o "$out/bunny_cpu.png" --size 640x640 --azimuth 0 --elevation 10
  run render --backend gl "$out/bunny.qxm" -o "$out/bunny.png" --size 640x640 --azimuth 0 --elevation 10 \
    --report "$out/bunny_render.json"
  run render --backend gl "$out/bunny.qxm" -o "$out/bunny_envmap.png" --size 640x640 --azimuth 0 --elevation 10 \
    --shading envmap
  # See the error: each patch coloured by its measured error (stored by fit), with a colour bar.
  run render --backend gl "$out/bunny.qxm" -o "$out/bunny_error.png" --size 640x640 --azimuth 0 --elevation 10 \
    --colour-by error --report "$out/bunny_error_render.json"
  # A mesh for MeshLab, Blender or a printer, within a stated distance of the rendered surface
  # (the default bound, 1e-3 of the diagonal; one grid, no doubling, to keep the demo short):
  # local refinement of the triangles, then of the grid cells where samples stay beyond the bound
  # (the ear tips), then moves towards what grazing views see (the per-ray blend shows them the
  # surface up to 1.7 bounds off where a head-on view sees it) bring the ../shared bunny within
  # the bound both ways, so a miss fails the demo (exit 7). The libcgal-demo copies are other
  # scans, not checked: there --allow-exceed lets the demo go on, and the report says what the
  # mesh reached.
  exceed=()
  [ "$bunny" = "$data/meshes/bunny.ply" ] || exceed=(--allow-exceed)
  run mesh "$out/bunny.qxm" -o "$out/bunny_mesh.ply" --max-refinements 0 "${exceed[@]}" \
    --report "$out/bunny_mesh.json"
else
  echo "demo: no bunny found (../shared/datasets or libcgal-demo); skipping the fit"
fi

if "$q" --help | grep -q "^  convert " && [ -n "$quads" ] && [ -f "$quads" ]; then
  run convert quads "$quads" -o "$out/quads.qxm" --report "$out/quads_convert.json"
  run render "$out/quads.qxm" -o "$out/quads.png" --size 640x640 --azimuth 150 --elevation 15 --shading envmap \
    --report "$out/quads_render.json"
fi

if [ -n "$molecule" ] && [ -f "$molecule" ]; then
  run convert skin "$molecule" -o "$out/molecule_skin.qxm" --no-water --report "$out/molecule_skin_convert.json"
  run render "$out/molecule_skin.qxm" -o "$out/molecule_skin.png" --size 640x640 --azimuth 30 --elevation 20 \
    --report "$out/molecule_skin_render.json"
fi
if [ -n "$skull" ] && [ -f "$skull" ]; then
  run convert volume "$skull" --iso 2.9 -o "$out/skull_iso.qxm" --colour 230,220,200 --report "$out/skull_convert.json"
  run render "$out/skull_iso.qxm" -o "$out/skull_iso.png" --size 640x640 --azimuth 200 --elevation 10 \
    --report "$out/skull_render.json"
fi
if [ -f "$lobster" ]; then
  run convert volume "$lobster" --iso 900 -o "$out/lobster_iso.qxm" --colour 220,90,60
  run render "$out/lobster_iso.qxm" -o "$out/lobster_iso.png" --size 800x600 --elevation 60 --shading envmap
fi
# The classic analytic test volume: quadratic patches against the exact surface (issue 6 table).
run convert volume --synth marschner-lobb --grid 41 --iso 0.5 -o "$out/marschner_lobb.qxm" \
  --report "$out/marschner_lobb_convert.json"
run render "$out/marschner_lobb.qxm" -o "$out/marschner_lobb.png" --size 640x640 --elevation 35 --shading envmap
# Finding the iso-value: info on a volume suggests Otsu's threshold; convert volume without --iso uses it.
run synth marschner-lobb -o "$out/marschner_lobb_volume.nhdr"
run info "$out/marschner_lobb_volume.nhdr"
run convert volume "$out/marschner_lobb_volume.nhdr" -o "$out/marschner_lobb_otsu.qxm" \
  --report "$out/marschner_lobb_otsu_convert.json"
run render "$out/marschner_lobb_otsu.qxm" -o "$out/marschner_lobb_otsu.png" --size 640x640 --elevation 35

run synth glyphs --count 400 -o "$out/glyphs.qxm"
run synth hyperboloid1 --resolution 12 -o "$out/hyperboloid.qxm"
run info "$out/glyphs.qxm"
run render --backend cpu "$out/glyphs.qxm" -o "$out/glyphs.png" --size 640x480 --report "$out/glyphs_render.json"
run render "$out/hyperboloid.qxm" -o "$out/hyperboloid.png" --size 480x480 --no-cull --elevation 25 \
  --report "$out/hyperboloid_render.json"
run render "$out/hyperboloid.qxm" -o "$out/hyperboloid_npr.png" --size 480x480 --no-cull --elevation 25 --shading npr
run render "$out/hyperboloid.qxm" -o "$out/hyperboloid_patches.png" --size 480x480 --no-cull --elevation 25 \
  --colour-by patch
if [ ! -f "$out/bunny_mesh.ply" ]; then
  run mesh "$out/hyperboloid.qxm" -o "$out/hyperboloid_mesh.ply" --report "$out/hyperboloid_mesh.json"
fi
echo "demo: images in $out/"
ls -1 "$out"/*.png "$out"/*_mesh.ply
