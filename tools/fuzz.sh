#!/usr/bin/env bash
# make fuzz: builds one libFuzzer target per I/O kit reader with clang (ASan + UBSan) and runs each
# for SECONDS (default 20) from the malformed corpus. Findings (crash-*, leak-*, timeout-*) are left
# in OUT/READER/ and make the script fail: turn each into a corpus file with its expected exit code.
# Usage: tools/fuzz.sh [OUT=out/fuzz] [SECONDS=20] [READERS="off obj stl ply xyz"]
set -euo pipefail
OUT=${1:-out/fuzz}
SECONDS_EACH=${2:-20}
READERS=${3:-"off obj stl ply xyz"}
CXX=${FUZZ_CXX:-$(command -v clang++ || command -v clang++-14 || true)}
[ -n "$CXX" ] || { echo "fuzz: clang++ not found (apt-get install clang)" >&2; exit 2; }
ROOT=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$OUT/obj"
FLAGS=(-std=c++20 -O1 -g -fsanitize=fuzzer-no-link,address,undefined -I"$ROOT" -I/usr/include/eigen3)
SOURCES=(core/io/read_off.cpp core/io/read_obj.cpp core/io/read_stl.cpp core/io/read_ply.cpp core/io/read_xyz.cpp
         core/io/ply.cpp core/io/file.cpp core/io/text_reader.cpp core/atomic_file.cpp core/log.cpp)
OBJECTS=()
for s in "${SOURCES[@]}"; do
  o="$OUT/obj/$(echo "$s" | tr / _).o"
  [ "$o" -nt "$ROOT/$s" ] || "$CXX" "${FLAGS[@]}" -c "$ROOT/$s" -o "$o"
  OBJECTS+=("$o")
done
status=0
for r in $READERS; do
  mkdir -p "$OUT/$r/corpus"
  "$CXX" "${FLAGS[@]}" -fsanitize=fuzzer -DQUADRIX_FUZZ_READER="$r" "$ROOT/tests/fuzz/fuzz_mesh_readers.cpp" \
    "${OBJECTS[@]}" -lfmt -lz -o "$OUT/$r/fuzz_$r"
  case $r in ply) glob='*.ply' ;; xyz) glob='*.xyz' ;; *) glob="*.$r" ;; esac
  find "$ROOT/tests/data/malformed/files" -maxdepth 1 -type f -name "$glob" -exec cp {} "$OUT/$r/corpus/" \;
  echo "fuzz: $r for ${SECONDS_EACH} s"
  if ! (cd "$OUT/$r" && ./"fuzz_$r" -max_total_time="$SECONDS_EACH" -max_len=65536 -rss_limit_mb=2048 \
        -print_final_stats=1 corpus > log.txt 2>&1); then
    echo "fuzz: $r found a failure, see $OUT/$r/log.txt and $OUT/$r/crash-*" >&2
    status=1
  fi
  grep -E "stat::number_of_executed_units|Done" "$OUT/$r/log.txt" | tail -1
done
exit $status
