#!/usr/bin/env bash
# Installs the Debian 12 packages visaudit needs to build, test and fetch its test data.
# Installs only what is missing; safe to run again. Needs root (or sudo).
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config ca-certificates
  libopenmesh-dev libembree-dev libcgal-dev libgmp-dev libmpfr-dev
  libopenimageio-dev libopenexr-dev libpng-dev zlib1g-dev libdeflate-dev nlohmann-json3-dev libcli11-dev libtbb-dev
  libtinygltf-dev libstb-dev libzip-dev libdraco-dev libmeshoptimizer-dev assimp-utils
  libgtest-dev libgmock-dev libbenchmark-dev
  libegl-dev libopengl-dev libgl1-mesa-dri
  parallel
  clang-14 libclang-rt-14-dev llvm-14
  chromium fonts-dejavu-core nodejs
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# npm (the browser test's installer, scripts/test.sh) is a package of its own in Debian but comes
# inside NodeSource's nodejs, which conflicts with Debian's npm: ask for it only when no npm runs.
command -v npm >/dev/null 2>&1 || missing+=(npm)
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
