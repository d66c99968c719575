#!/usr/bin/env bash
# The PVS audit's floor (issue 15): every cluster of oa_thor (2,825) in at most 60 s wall on 2 cores
# with the default settings, and where the time goes. Runs `visaudit pvs-audit` on the map at the
# default settings and at the quick and thorough ones below, 2 threads, and prints per run the wall
# time, the rays, the rays per second and the summary's split (eye points, Embree, BSP walk, summed
# over the threads). PASS/FAIL is printed beside the default run; the exit status does not depend on
# it. Run it on a quiet machine. Never run by the tests.
#
#   bash bench/pvs_audit.sh [MAP] [--threads N]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${BUILD:-$ROOT/build}"
MAP="${1:-$ROOT/data/openarena/pak6-patch088.pk3:maps/oa_thor.bsp}"
THREADS=2
if [ "${2:-}" = "--threads" ]; then THREADS="$3"; fi
if [ ! -f "$BUILD/CMakeCache.txt" ]; then
  cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
cmake --build "$BUILD" -j"$(nproc)" --target visaudit >&2
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
echo "pvs-audit of $MAP, $THREADS threads ($(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg))"
printf '%-42s %9s %12s %10s  %s\n' settings "wall (s)" rays "Mrays/s" "split (thread ms)"
for settings in "default:" "quick:--samples 16 --resolution 8" "thorough:--samples 64 --resolution 16"; do
  name="${settings%%:*}"
  flags="${settings#*:}"
  start=$(date +%s.%N)
  # shellcheck disable=SC2086
  "$BUILD/visaudit" pvs-audit "$MAP" --threads "$THREADS" --out "$OUT/$name" $flags >"$OUT/$name.txt"
  end=$(date +%s.%N)
  wall=$(echo "$end - $start" | bc -l)
  rays=$(sed -n 's/.* eye points, \([0-9,]*\) rays$/\1/p' "$OUT/$name.txt" | tr -d ,)
  split=$(sed -n 's/^  time *//p' "$OUT/$name.txt")
  verdict=""
  if [ "$name" = default ]; then
    verdict=$(echo "$wall <= 60" | bc -l | sed 's/1/PASS (<= 60 s)/; s/^0$/FAIL (> 60 s)/')
  fi
  printf '%-42s %9.1f %12s %10.2f  %s %s\n' "$name ${flags:-(32 x 864 rays)}" "$wall" "$rays" \
    "$(echo "$rays / $wall / 1000000" | bc -l)" "$split" "$verdict"
done
