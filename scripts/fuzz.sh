#!/usr/bin/env bash
# The `fuzz` command: builds the loaders' libFuzzer targets (fuzz/, clang 14 with ASan + UBSan) and
# runs them from a seed corpus of real files.
#
#   scripts/fuzz.sh [--seconds N] [--parallel P] [--build DIR] [TARGET ...]
#       Runs each target (all by default) for N seconds (default 600), P at a time (default 1), with
#       the corpus kept in fuzz/corpus/TARGET (gitignored; it grows from run to run). Prints a table:
#       executions, exec/s, coverage (cov/ft), corpus size, findings.
#   scripts/fuzz.sh --smoke [--runs N] [TARGET ...]
#       CI's check: N executions per target (default 3000) mutating the small seeds only (no data/,
#       no saved corpus); exits non-zero on any finding.
#
# Targets: scene_json views_json route_json budget_json obj ply off stl gltf glb bsp pk3 image.
# Findings (crash-*, leak-*, timeout-*, oom-*) are copied to fuzz/findings/TARGET/ with the log;
# each becomes a fix in the loader and a literal case in tests/test_fuzz_regressions.cpp.
# Needs clang-14 and libclang-rt-14-dev (scripts/install-deps.sh).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"

ALL=(scene_json views_json route_json budget_json obj ply off stl gltf glb bsp pk3 image)
seconds=600 smoke=0 runs=3000 parallel=1 build="$root/build-fuzz" targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds="$2"; shift 2 ;;
    --smoke) smoke=1; shift ;;
    --runs) runs="$2"; shift 2 ;;
    --parallel) parallel="$2"; shift 2 ;;
    --build) build="$(realpath -m "$2")"; shift 2 ;;
    -h|--help) sed -n '2,18p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    -*) echo "fuzz.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
    *)
      if [[ " ${ALL[*]} " != *" $1 "* ]]; then
        echo "fuzz.sh: unknown target '$1'; targets: ${ALL[*]}" >&2; exit 2
      fi
      targets+=("$1"); shift ;;
  esac
done
[ ${#targets[@]} -gt 0 ] || targets=("${ALL[@]}")

# ---- Build ------------------------------------------------------------------------------------
CXX_FUZZ="${CXX_FUZZ:-clang++-14}"
command -v "$CXX_FUZZ" >/dev/null || { echo "fuzz.sh: $CXX_FUZZ not found; run scripts/install-deps.sh" >&2; exit 2; }
# RelWithDebInfo without NDEBUG: assertions stay on, and stack traces have lines.
cmake -S "$root" -B "$build" -DCMAKE_CXX_COMPILER="$CXX_FUZZ" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g" -DVISAUDIT_FUZZ=ON -DVISAUDIT_TESTS=OFF -DVISAUDIT_BENCH=OFF >/dev/null
cmake --build "$build" -j"$(nproc 2>/dev/null || echo 2)" --target "${targets[@]/#/fuzz_}" >/dev/null

# ---- Seeds ------------------------------------------------------------------------------------
# Small seeds: files of the repository and generated ones (fuzz/make_seeds.py). Data seeds: the
# fetched real levels (scripts/fetch-data.sh), only for the long runs.
seeds="$build/fuzz-seeds"
rm -rf "$seeds"
for t in "${ALL[@]}"; do mkdir -p "$seeds/small/$t" "$seeds/data/$t"; done
python3 "$root/fuzz/make_seeds.py" "$seeds/small" "$root/tests/data/tiny.gltf"
cp "$root"/examples/*.scene.json "$seeds/small/scene_json/"
cp "$root"/examples/*.views.json "$root"/tests/browser/*.views.json "$seeds/small/views_json/"
cp "$root"/examples/*.budget.json "$seeds/small/budget_json/"
cp "$root"/examples/*.route.json "$root"/tests/browser/*.route.json "$seeds/small/route_json/"
for e in obj ply off stl; do cp "$root"/examples/meshes/*."$e" "$root"/tests/data/*."$e" "$seeds/small/$e/"; done
cp "$root"/tests/data/*.gltf "$seeds/small/gltf/"
# Issue 16: a glTF whose extras nest past --max-json-depth (refused before tinygltf parses it).
python3 -c 'import sys; n = 600; sys.stdout.write("{\"asset\":{\"version\":\"2.0\"},\"extras\":" + "[" * n + "]" * n + "}")' \
  > "$seeds/small/gltf/deep-extras.gltf"
# ... and every other JSON target's input nested past it (scene, views, budget: json::checkDepth).
python3 -c 'import sys; n = 600; sys.stdout.write("{\"format\":\"visaudit-scene/1\",\"x\":" + "[" * n + "]" * n + "}")' \
  > "$seeds/small/scene_json/deep.scene.json"
python3 -c 'import sys; n = 600; sys.stdout.write("{\"views\":[{\"x\":" + "[" * n + "]" * n + "}]}")' \
  > "$seeds/small/views_json/deep.views.json"
python3 -c 'import sys; n = 600; sys.stdout.write("{\"format\":\"visaudit-budget/1\",\"x\":" + "{\"a\":" * n + "1" + "}" * n + "}")' \
  > "$seeds/small/budget_json/deep.budget.json"
python3 -c 'import sys; n = 600; sys.stdout.write("{\"format\":\"visaudit-route/1\",\"keyframes\":" + "[" * n + "]" * n + "}")' \
  > "$seeds/small/route_json/deep.route.json"
cp "$root"/tests/data/fuzz/* "$seeds/small/" 2>/dev/null || true
if [ -f data/castle/level/level-dungeon.gltf ]; then
  cp data/castle/level/level-dungeon.gltf "$seeds/data/gltf/"
  python3 "$root/fuzz/make_seeds.py" "$seeds/data" data/castle/level/level-dungeon.gltf
fi
# The dungeon's Draco, meshopt and quantized GLBs (scripts/make-gltf-variants.sh): libdraco's and
# libmeshoptimizer's inputs, for the long runs.
cp data/castle/variants/*.glb "$seeds/data/glb/" 2>/dev/null || true
[ -f data/cgal/elephant.off ] && cp data/cgal/elephant.off "$seeds/data/off/"
if [ -f data/openarena/pak1-maps.pk3 ]; then
  # The smallest real maps (0.7-0.8 MB) and a small archive of one of them.
  python3 - "$seeds/data" <<'EOF_PY'
import sys, zipfile
out = sys.argv[1]
with zipfile.ZipFile('data/openarena/pak1-maps.pk3') as pak:
    for m in ('q3dm6ish', 'oa_ctf2'):
        open('%s/bsp/%s.bsp' % (out, m), 'wb').write(pak.read('maps/%s.bsp' % m))
    with zipfile.ZipFile(out + '/pk3/q3dm6ish.pk3', 'w', zipfile.ZIP_DEFLATED) as z:
        z.writestr('maps/q3dm6ish.bsp', pak.read('maps/q3dm6ish.bsp'))
EOF_PY
fi

dict_of() {
  case "$1" in
    scene_json|views_json|route_json|budget_json) echo json ;;
    glb) echo gltf ;;
    *) echo "$1" ;;
  esac
}

# ---- Run --------------------------------------------------------------------------------------
results="$build/fuzz-results"
mkdir -p "$results"
run_one() {
  local t="$1" bin="$build/fuzz/fuzz_$1" findings="$root/fuzz/findings/$1" log="$results/$1.log"
  local work corpus args
  mkdir -p "$findings"
  work="$(mktemp -d "$results/$t.XXXXXX")"
  args=(-dict="$root/fuzz/dict/$(dict_of "$t").dict" -artifact_prefix="$work/" -timeout=10
        -rss_limit_mb=2560 -malloc_limit_mb=2048 -close_fd_mask=1 -print_final_stats=1)
  if [ "$smoke" = 1 ]; then
    mkdir -p "$work/corpus"
    args+=(-runs="$runs" "$work/corpus" "$seeds/small/$t")
  else
    corpus="$root/fuzz/corpus/$t"
    mkdir -p "$corpus"
    # libFuzzer truncates seeds to 1 MB unless told otherwise: room for the castle level's GLB.
    [ "$t" = glb ] && args+=(-max_len=1500000)
    args+=(-max_total_time="$seconds" "$corpus" "$seeds/small/$t" "$seeds/data/$t")
  fi
  local rc=0
  ASAN_OPTIONS="detect_leaks=1:allocator_may_return_null=0" UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1" \
    nice -n 5 "$bin" "${args[@]}" </dev/null >"$log" 2>&1 || rc=$?
  local found=0
  for f in "$work"/crash-* "$work"/leak-* "$work"/timeout-* "$work"/oom-* "$work"/slow-unit-*; do
    [ -e "$f" ] || continue
    cp "$f" "$findings/"
    found=$((found + 1))
  done
  if [ "$found" -gt 0 ] || [ "$rc" -ne 0 ]; then
    cp "$log" "$findings/$(date +%Y%m%d-%H%M%S).log"
    [ "$found" -gt 0 ] || found="exit $rc"
  fi
  rm -rf "$work"
  # The last status line ("#N DONE cov: C ft: F corp: K/S ...") and the final stats.
  local last execs speed
  last="$(grep -E '^#[0-9]+' "$log" | tail -1 || true)"
  execs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")"
  speed="$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log")"
  printf '%-12s %10s %8s %8s %8s %10s  %s\n' "$t" "${execs:-?}" "${speed:-?}" \
    "$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")" "$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")" \
    "$(sed -n 's/.* corp: \([0-9]*\/[0-9a-zA-Z]*\).*/\1/p' <<<"$last")" "$found" >"$results/$t.row"
  [ "$found" = 0 ]
}

start=$(date +%s)
printf '%-12s %10s %8s %8s %8s %10s  %s\n' target execs exec/s cov ft corpus findings
failed=0
pids=()
for t in "${targets[@]}"; do
  run_one "$t" &
  pids+=($!)
  if [ ${#pids[@]} -ge "$parallel" ]; then
    wait "${pids[0]}" || failed=1
    pids=("${pids[@]:1}")
  fi
done
for p in "${pids[@]}"; do wait "$p" || failed=1; done
for t in "${targets[@]}"; do cat "$results/$t.row"; done
echo "fuzz.sh: $(( $(date +%s) - start )) s; logs in $results; findings in fuzz/findings/"
if [ "$failed" -ne 0 ]; then
  echo "fuzz.sh: FINDINGS (see fuzz/findings/)" >&2
  exit 1
fi
