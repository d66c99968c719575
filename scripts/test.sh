#!/usr/bin/env bash
# The second README command: installs what is missing, builds, fetches the real test scenes from
# Debian packages, and runs the whole test suite with CTest, then again under the sanitizers.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/fetch-data.sh
bash scripts/build.sh
# The browser test's one dependency, playwright-core, at the version tests/browser/package-lock.json
# pins; it drives Debian's chromium (/usr/bin/chromium), so no browser is downloaded.
(cd tests/browser && PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --no-audit --no-fund --loglevel=error)
jobs=$(nproc 2>/dev/null || echo 2)
# The whole suite.
(cd build && ctest --output-on-failure -j"$jobs")
# The whole suite again under AddressSanitizer + UndefinedBehaviorSanitizer (gcc, -O1; any report
# fails the run: tests/CMakeLists.txt). The browser tests are left out: they check the page in
# chromium, and the program runs they make are the CLI tests' too.
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Release -DVISAUDIT_SANITIZE=ON -DVISAUDIT_BENCH=OFF >/dev/null
cmake --build build-asan -j"$jobs" --target visaudit_tests
(cd build-asan && ctest --output-on-failure -j"$jobs" -LE browser)
# The loaders' libFuzzer targets (clang 14, ASan + UBSan): 3000 executions each from the seeds;
# any crash, hang or leak fails the run (scripts/fuzz.sh; long runs are `scripts/fuzz.sh --seconds N`).
bash scripts/fuzz.sh --smoke
