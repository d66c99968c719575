#!/usr/bin/env bash
# Installs the Debian 12 packages visaudit needs to build, test and fetch its test data.
# Installs only what is missing; safe to run again. Needs root (or sudo).
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config ca-certificates
  libopenmesh-dev libembree-dev libcgal-dev libgmp-dev libmpfr-dev
  libopenimageio-dev nlohmann-json3-dev libcli11-dev libtbb-dev
  libtinygltf-dev libstb-dev libzip-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  parallel
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
