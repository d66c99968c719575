#!/usr/bin/env bash
# Builds visaudit as it was when issue 18 was filed (commit b9c9599, the last one before its work
# began) and prints the binary's path. bench/run.sh --baseline runs it beside today's build in the
# level section, so "5x faster than the 118 s baseline" is measured on the machine at hand (118 s
# was measured on 2026-11-24's machine; a slower or faster machine moves both runs alike).
#
#   bash bench/issue18_baseline.sh            # prints $BUILD/issue18-baseline/build/visaudit
#
# Needs the repository's history (a clone, not an export). The sources are exported with
# `git archive` into $BUILD/issue18-baseline/src (no worktree to clean up); the build is cached.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${BUILD:-$ROOT/build}"
COMMIT=b9c9599
DIR="$BUILD/issue18-baseline"
if ! git -C "$ROOT" cat-file -e "$COMMIT^{commit}" 2>/dev/null; then
  echo "issue18_baseline.sh: commit $COMMIT is not in $ROOT's history (a shallow clone?); fetch it with" \
       "'git fetch --unshallow', or run bench/run.sh without --baseline" >&2
  exit 2
fi
if [ ! -x "$DIR/build/visaudit" ]; then
  rm -rf "$DIR/src"
  mkdir -p "$DIR/src"
  git -C "$ROOT" archive "$COMMIT" | tar -x -C "$DIR/src"
  echo "issue18_baseline.sh: building visaudit at $COMMIT in $DIR/build (a few minutes)" >&2
  cmake -S "$DIR/src" -B "$DIR/build" -DCMAKE_BUILD_TYPE=Release -DVISAUDIT_BENCH=OFF >/dev/null
  cmake --build "$DIR/build" -j"$(nproc)" --target visaudit >&2
fi
echo "$DIR/build/visaudit"
