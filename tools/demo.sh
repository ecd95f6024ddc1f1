#!/usr/bin/env bash
# make demo: builds analytic models and renders them with the CPU reference ray caster.
set -euo pipefail
q=${1:?quadrix binary}; out=${2:-out/demo}
mkdir -p "$out"
run() { echo "+ quadrix ${*}"; "$q" "$@"; }
run synth glyphs --count 400 -o "$out/glyphs.qxm"
run synth hyperboloid1 --resolution 12 -o "$out/hyperboloid.qxm"
run synth slim-sphere --count 400 -o "$out/slim_sphere.qxm"
run info "$out/glyphs.qxm"
run render --backend cpu "$out/glyphs.qxm" -o "$out/glyphs.png" --size 640x480 --report "$out/glyphs_render.json"
run render --backend cpu "$out/hyperboloid.qxm" -o "$out/hyperboloid.png" --size 480x480 --no-cull --elevation 25
run render --backend cpu "$out/slim_sphere.qxm" -o "$out/slim_sphere.png" --size 480x480 --depth-out "$out/slim_sphere_depth.pfm"
echo "demo: images in $out/"
ls -1 "$out"/*.png
