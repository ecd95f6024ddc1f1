#!/usr/bin/env bash
# make demo: the pipeline on real and analytic data. Fits the Stanford bunny (SLIM) and renders it
# with the CPU reference and with the GL three-pass SLIM renderer (OSMesa/EGL), converts a quad mesh into tetrahedron-clipped quadrics and ray-casts it
# with OpenGL (OSMesa/EGL), and renders analytic glyph and hyperboloid models.
set -euo pipefail
q=${1:?quadrix binary}; out=${2:-out/demo}
here=$(cd "$(dirname "$0")/.." && pwd)
data=${QUADRIX_DATASETS:-$here/../shared/datasets}
mkdir -p "$out"
run() { echo "+ quadrix ${*}"; "$q" "$@"; }

# Real data: ../shared/datasets, or the copies Debian's libcgal-demo ships.
bunny="$data/meshes/bunny.ply"
quads="$data/quads/spot_quadrangulated.obj"
if [ ! -f "$bunny" ] && [ -f /usr/share/doc/libcgal-dev/data.tar.gz ]; then
  mkdir -p "$out/data"
  tar -xzf /usr/share/doc/libcgal-dev/data.tar.gz -C "$out/data" --wildcards '*bunny*' '*quad*' 2>/dev/null || true
  bunny=$(find "$out/data" -name 'bunny*.off' -o -name 'bunny*.ply' -o -name 'bunny*.xyz' | head -n1)
  quads=$(find "$out/data" -name 'cube_quad.off' -o -name 'torus_quad.off' | head -n1)
fi

if [ -n "$bunny" ] && [ -f "$bunny" ]; then
  run fit "$bunny" -o "$out/bunny.qxm" --max-error 1e-3 --report "$out/bunny_fit.json"
  run render --backend cpu "$out/bunny.qxm" -o "$out/bunny_cpu.png" --size 640x640 --azimuth 0 --elevation 10
  run render --backend gl "$out/bunny.qxm" -o "$out/bunny.png" --size 640x640 --azimuth 0 --elevation 10 \
    --report "$out/bunny_render.json"
  run render --backend gl "$out/bunny.qxm" -o "$out/bunny_envmap.png" --size 640x640 --azimuth 0 --elevation 10 \
    --shading envmap
else
  echo "demo: no bunny found (../shared/datasets or libcgal-demo); skipping the fit"
fi

if "$q" --help | grep -q "^  convert " && [ -n "$quads" ] && [ -f "$quads" ]; then
  run convert quads "$quads" -o "$out/quads.qxm" --report "$out/quads_convert.json"
  run render "$out/quads.qxm" -o "$out/quads.png" --size 640x640 --azimuth 150 --elevation 15 --shading envmap \
    --report "$out/quads_render.json"
fi

run synth glyphs --count 400 -o "$out/glyphs.qxm"
run synth hyperboloid1 --resolution 12 -o "$out/hyperboloid.qxm"
run info "$out/glyphs.qxm"
run render --backend cpu "$out/glyphs.qxm" -o "$out/glyphs.png" --size 640x480 --report "$out/glyphs_render.json"
run render "$out/hyperboloid.qxm" -o "$out/hyperboloid.png" --size 480x480 --no-cull --elevation 25 \
  --report "$out/hyperboloid_render.json"
run render "$out/hyperboloid.qxm" -o "$out/hyperboloid_npr.png" --size 480x480 --no-cull --elevation 25 --shading npr
echo "demo: images in $out/"
ls -1 "$out"/*.png
