#!/usr/bin/env bash
# The first README command: installs what is missing, builds, and analyzes the built-in demo scene.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh --target visaudit
build/visaudit analyze --out visaudit-report "$@"
