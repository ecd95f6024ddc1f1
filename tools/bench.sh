#!/usr/bin/env bash
# make bench: SLIM against OpenMesh decimation and CGAL Poisson, both sides of the error
# (bench fit), then the fitted bunny against its same-error decimated mesh in the renderer
# (bench render). Usage: tools/bench.sh QUADRIX OUT_DIR [extra bench-fit options]
set -euo pipefail
q="$1"; out="$2"; shift 2
mkdir -p "$out"
"$q" bench fit --out "$out/fit" --keep-models "$@"
model="$out/fit/bunny_0.001.qxm"
if [ -f "$model" ]; then
  "$q" bench render "$model" --baseline-mesh "$out/fit/bunny_0.001_decimated.off" --out "$out/render"
fi
