#!/usr/bin/env bash
# The second README command: installs what is missing, builds, fetches the real test scenes from
# Debian packages, and runs the whole test suite with CTest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/fetch-data.sh
bash scripts/build.sh
# The browser test's one dependency, playwright-core, at the version tests/browser/package-lock.json
# pins; it drives Debian's chromium (/usr/bin/chromium), so no browser is downloaded.
(cd tests/browser && PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --no-audit --no-fund --loglevel=error)
cd build
ctest --output-on-failure -j"$(nproc 2>/dev/null || echo 2)"
