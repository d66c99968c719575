#!/usr/bin/env bash
# The benchmark of issue 8: one command, one table, every figure beside its peer measured in the
# same run (z-buffer vs Mesa llvmpipe, castPrimary vs raw rtcIntersect16, loading, analyze end to
# end against its own timings, and a 10k..10M triangles x 1..64 views scaling table).
#
#   bash bench/run.sh                      # everything (the 10M x 64 views case alone takes minutes)
#   bash bench/run.sh --quick              # 3 repetitions; scaling without 10M triangles and 64 views
#   bash bench/run.sh --sections zbuffer,llvmpipe,raycast,pipeline,load,analyze,level,scaling [--reps N] [--keep]
#   bash bench/run.sh --baseline ...       # the level section also runs issue 18's start (built once by
#                                          # bench/issue18_baseline.sh) in the same run, for its 5x floor
#
# Builds visaudit and bench_table (Release) in $BUILD (default: build/), then runs
# $BUILD/bench/bench_table; progress goes to stderr, the table to stdout. Floors are printed as
# PASS/FAIL beside each figure; the exit status does not depend on them. Never run by the tests.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${BUILD:-$ROOT/build}"
if [ ! -f "$BUILD/CMakeCache.txt" ]; then
  cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
cmake --build "$BUILD" -j"$(nproc)" --target visaudit bench_table >&2
args=()
for a in "$@"; do
  if [ "$a" = "--baseline" ]; then
    args+=(--baseline "$(BUILD="$BUILD" bash "$ROOT/bench/issue18_baseline.sh")")
  else
    args+=("$a")
  fi
done
exec "$BUILD/bench/bench_table" --visaudit "$BUILD/visaudit" --data "$ROOT/data" "${args[@]}"
