#!/usr/bin/env bash
# make fuzz: builds one libFuzzer binary for every reader with Debian's clang (ASan + UBSan, from
# tests/fuzz/fuzz_readers.cpp; OUT/READER/fuzz_READER are hard links to OUT/fuzz_readers, which
# picks its reader by its name) and runs each reader for SECONDS (default 20) from the malformed
# corpus (tests/data/malformed/files), the valid seeds (tests/fuzz/seeds/READER) and what earlier
# runs found (OUT/READER/corpus). Findings (crash-*, leak-*, timeout-*, oom-*) stay in OUT/READER/
# and make the script fail: turn each into a corpus file with its expected exit code. Each run
# adds a line "SECONDS EXECUTIONS COVERAGE FEATURES" to OUT/READER/runs.
# Usage: tools/fuzz.sh [--build|--run|--check] [OUT=out/fuzz] [SECONDS=20] [READERS="all"]
#   --build: only build; --run: only run (built before); --check: exit 77 (skip) when clang++ or
#   libFuzzer is missing, 0 when present. FUZZ_NICE=N runs the fuzzers under nice -n N.
#   FUZZ_TIMEOUT=S: an input running longer (wall clock) is a finding (default 20); raise it with
#   a high FUZZ_NICE on a busy machine, where a starved fuzzer can stall past 20 s on any input.
#   FUZZ_SEED=N: libFuzzer's -seed (default 0: a random seed each run, growing OUT/READER/corpus);
#   the smoke tests set 1: each run starts from the checked-in inputs only and tries the same
#   inputs in the same order (only how far it gets in SECONDS varies with the machine and load).
set -euo pipefail
MODE=all
case ${1:-} in --build|--run|--check) MODE=${1#--}; shift ;; esac
OUT=${1:-out/fuzz}
SECONDS_EACH=${2:-20}
ALL="off obj stl ply xyz pts qxm slim2t mesh tetgen values nrrd nhdr inr inrgz cin pdb csv png pfm implicit"
READERS=${3:-all}
[ "$READERS" = all ] && READERS=$ALL
CXX=${FUZZ_CXX:-$(command -v clang++ || command -v clang++-14 || true)}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
if [ -z "$CXX" ]; then
  echo "fuzz: SKIPPED: clang++ not found (apt-get install clang libclang-rt-14-dev)" >&2
  exit 77
fi
mkdir -p "$OUT/build"
if [ "$MODE" = check ] || [ "$MODE" = build ] || [ "$MODE" = all ]; then
  printf 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char*, unsigned long) { return 0; }\n' > "$OUT/build/probe.cpp"
  if ! "$CXX" -fsanitize=fuzzer,address,undefined "$OUT/build/probe.cpp" -o "$OUT/build/probe" 2> "$OUT/build/probe.log"; then
    echo "fuzz: SKIPPED: $CXX cannot link libFuzzer (apt-get install libclang-rt-14-dev): $(head -c 300 "$OUT/build/probe.log")" >&2
    exit 77
  fi
  [ "$MODE" = check ] && exit 0
fi
FLAGS=(-std=c++20 -O1 -g -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined
       -I"$ROOT" -I/usr/include/eigen3 -DNDEBUG)
if [ "$MODE" != run ]; then
  SOURCES=($(cd "$ROOT" && ls core/*.cpp core/io/*.cpp core/implicit/*.cpp)
           convert/volume.cpp convert/tetmesh_io.cpp convert/balls.cpp convert/molecule.cpp
           convert/read_molecule.cpp convert/ellipsoids_csv.cpp tests/fuzz/fuzz_readers.cpp)
  OBJECTS=()
  STALE=()
  for s in "${SOURCES[@]}"; do
    o="$OUT/build/$(echo "$s" | tr / _).o"
    # Rebuilt when the source or any header of the tree is newer (coarse but safe).
    if [ ! -e "$o" ] || [ -n "$(find "$ROOT/$s" "$ROOT/core" "$ROOT/convert" -name '*.h' -newer "$o" -print -quit)" ] ||
       [ "$ROOT/$s" -nt "$o" ]; then
      STALE+=("$s")
    fi
    OBJECTS+=("$o")
  done
  # FUZZ_JOBS compilers at once (default 2). gemmi's headers do not compile as C++20 with clang 14
  # (std::vector of an incomplete type in a constexpr destructor): read_molecule.cpp as C++17, and
  # without UBSan's shift-base check: gemmi's ialpha4_id shifts a signed char left (`s[0] << 24`),
  # undefined in C++17 for bytes >= 0x80 but defined in C++20, the language the real build uses
  # (found by fuzzing pdb: a one-byte file 0xf7).
  if [ ${#STALE[@]} -gt 0 ]; then
    printf '%s\n' "${STALE[@]}" | xargs -P "${FUZZ_JOBS:-2}" -I{} sh -c \
      'o="$1/build/$(echo "$2" | tr / _).o"; shift 2; case "$0" in *read_molecule.cpp) set -- "$@" -std=c++17 -fno-sanitize=shift-base ;; esac
       exec "$@" -c "$0" -o "$o"' "$ROOT/{}" "$OUT" {} "$CXX" "${FLAGS[@]}"
  fi
  "$CXX" "${FLAGS[@]}" -fsanitize=fuzzer "${OBJECTS[@]}" -lOpenMeshCore -lfmt -lz -lpng -ljpeg -ltbb -o "$OUT/fuzz_readers"
  for r in $READERS; do
    mkdir -p "$OUT/$r"
    ln -f "$OUT/fuzz_readers" "$OUT/$r/fuzz_$r"
  done
fi
[ "$MODE" = build ] && exit 0
status=0
for r in $READERS; do
  if [ ! -x "$OUT/$r/fuzz_$r" ]; then
    echo "fuzz: SKIPPED: $OUT/$r/fuzz_$r is not built (tools/fuzz.sh --build)" >&2
    exit 77
  fi
  # With a fixed FUZZ_SEED (the smoke tests) the run starts from the checked-in inputs alone, in a
  # fresh folder, and writes what it finds to another fresh one: the same inputs in the same order
  # on every machine (only how far it gets in SECONDS depends on the machine's speed and load).
  # Otherwise it grows OUT/READER/corpus from run to run.
  corpus="$OUT/$r/corpus"
  dirs=(corpus)
  if [ "${FUZZ_SEED:-0}" != 0 ]; then
    corpus="$OUT/$r/smoke-seeds"
    rm -rf "$corpus" "$OUT/$r/smoke-found"
    mkdir -p "$OUT/$r/smoke-found"
    dirs=(smoke-found smoke-seeds)
  fi
  mkdir -p "$corpus"
  case $r in
    ply) glob='*.ply' ;; xyz) glob='*.xyz' ;; pts) glob='*.pts' ;; qxm) glob='*.qxm' ;; slim2t) glob='*.slim2t' ;;
    mesh) glob='*.mesh' ;; tetgen) glob='*.node' ;; values) glob='values*.txt' ;; nrrd) glob='*.nrrd' ;;
    nhdr) glob='*.nhdr' ;; inr) glob='*.inr' ;; inrgz) glob='*.inr.gz' ;; cin) glob='*.cin' ;; pdb) glob='*.pdb' ;;
    csv) glob='*.csv' ;; png) glob='*.png' ;; pfm) glob='*.pfm' ;; implicit) glob='*.implicit' ;; *) glob="*.$r" ;;
  esac
  find "$ROOT/tests/data/malformed/files" "$ROOT/tests/data/malformed" -maxdepth 1 -type f -name "$glob" \
    -exec cp {} "$corpus/" \;
  [ -d "$ROOT/tests/fuzz/seeds/$r" ] && cp "$ROOT/tests/fuzz/seeds/$r"/* "$corpus/"
  [ -n "$(ls -A "$corpus")" ] || printf '0\n' > "$corpus/seed"
  echo "fuzz: $r for ${SECONDS_EACH} s"
  start=$(date +%s)
  if ! (cd "$OUT/$r" && nice -n "${FUZZ_NICE:-0}" ./"fuzz_$r" -max_total_time="$SECONDS_EACH" -max_len=65536 \
        -rss_limit_mb=2048 -timeout="${FUZZ_TIMEOUT:-20}" -seed="${FUZZ_SEED:-0}" -print_final_stats=1 "${dirs[@]}" > log.txt 2>&1); then
    echo "fuzz: $r found a failure, see $OUT/$r/log.txt and $OUT/$r/crash-*" >&2
    grep -m3 -E "ERROR|runtime error|terminate|deadly" "$OUT/$r/log.txt" >&2 || true
    status=1
  fi
  execs=$(grep -E "stat::number_of_executed_units" "$OUT/$r/log.txt" | tail -1 | awk '{print $2}')
  last=$(grep -E "^#[0-9]+.*cov: " "$OUT/$r/log.txt" | tail -1)
  cov=$(echo "$last" | sed -n 's/.* cov: \([0-9]*\).*/\1/p')
  ft=$(echo "$last" | sed -n 's/.* ft: \([0-9]*\).*/\1/p')
  echo "$(( $(date +%s) - start )) ${execs:-0} ${cov:-0} ${ft:-0}" >> "$OUT/$r/runs"
  echo "fuzz: $r: ${execs:-0} runs, coverage ${cov:-?} edges, $(awk '{s+=$1; e+=$2} END {print s " s, " e " runs"}' \
"$OUT/$r/runs") in total in $OUT/$r"
done
exit $status
