#!/usr/bin/env bash
# Makes compressed and quantized variants of the test level (data/castle/level/level-dungeon.gltf,
# 25038 triangles) with real glTF optimizers, for tests/test_gltf.cpp (LoadGltfVariants):
#   level-dungeon.draco.glb             gltf-transform draco    KHR_draco_mesh_compression, 14-bit positions
#   level-dungeon.meshopt.glb           gltfpack -cc            EXT_meshopt_compression + KHR_mesh_quantization
#   level-dungeon.meshopt.gltf (+ .bin) gltfpack -cc            the same as .gltf, with a fallback buffer without data
#   level-dungeon.gt-meshopt.glb        gltf-transform meshopt  EXT_meshopt_compression, normalized int16 positions
#   level-dungeon.quantized.glb         gltfpack                KHR_mesh_quantization, integer uint16 positions
#   level-dungeon.quantized-norm.glb    gltfpack -vpn           KHR_mesh_quantization, normalized uint16 positions
#   level-dungeon.gt-quantized.glb      gltf-transform quantize KHR_mesh_quantization, normalized int16 positions
# Every tool quantizes positions to 14 bits (-vp 14, --quantize-position 14); the test derives its
# tolerance from that and the level's bounds. The tools come from the npm registry at the versions
# scripts/gltf-tools/package-lock.json pins (gltfpack 0.18.0 matches Debian's libmeshoptimizer 0.18),
# installed with `npm ci --ignore-scripts` into .cache/gltf-tools. The level's textures are not fetched
# (visaudit reads none), and the tools refuse a file whose images are missing, so they get a copy
# without images, textures and samplers (its geometry, nodes and materials as they are).
# Idempotent: nothing is done when the variants in place were made from the same lock file and script.
# Non-interactive (works in CI). Called by scripts/fetch-data.sh.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
DATA="${VISAUDIT_DATA_DIR:-$ROOT/data}"
CACHE="${VISAUDIT_CACHE_DIR:-$ROOT/.cache}/gltf-tools"
TOOLS="$ROOT/scripts/gltf-tools"
SRC="$DATA/castle/level"
OUT="$DATA/castle/variants"

if [[ ! -s "$SRC/level-dungeon.gltf" || ! -s "$SRC/level-dungeon.bin" ]]; then
  echo "make-gltf-variants: $SRC/level-dungeon.gltf is missing (scripts/fetch-data.sh fetches it)" >&2
  exit 1
fi
stamp="$(cat "$TOOLS/package-lock.json" "${BASH_SOURCE[0]}" | sha256sum | cut -d' ' -f1)"
if [[ -f "$OUT/STAMP" && "$(cat "$OUT/STAMP")" == "$stamp" ]]; then
  echo "make-gltf-variants: $OUT already made with these tools"
  exit 0
fi
for tool in node npm; do
  command -v "$tool" >/dev/null || { echo "make-gltf-variants: $tool is missing (scripts/install-deps.sh installs nodejs)" >&2; exit 1; }
done

# The tools, at the pinned versions (reinstalled only when the lock file changed).
mkdir -p "$CACHE"
if ! cmp -s "$TOOLS/package-lock.json" "$CACHE/package-lock.json" || [[ ! -d "$CACHE/node_modules" ]]; then
  cp "$TOOLS/package.json" "$TOOLS/package-lock.json" "$CACHE/"
  (cd "$CACHE" && npm ci --ignore-scripts --no-audit --no-fund --loglevel=error)
fi
GLTFPACK="$CACHE/node_modules/.bin/gltfpack"
GLTF_TRANSFORM="$CACHE/node_modules/.bin/gltf-transform"

tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/in" "$tmp/out"
# The level without images (see above); its buffer beside it under its own name.
node - "$SRC/level-dungeon.gltf" "$tmp/in/level-dungeon.gltf" <<'EOF'
const fs = require("fs");
const [src, dst] = process.argv.slice(2);
const g = JSON.parse(fs.readFileSync(src, "utf8"));
delete g.images; delete g.textures; delete g.samplers;
const strip = (o) => {
  if (o && typeof o === "object")
    for (const k of Object.keys(o)) { if (/Texture$/.test(k)) delete o[k]; else strip(o[k]); }
};
strip(g.materials);
fs.writeFileSync(dst, JSON.stringify(g));
EOF
cp "$SRC/level-dungeon.bin" "$tmp/in/"
in="$tmp/in/level-dungeon.gltf"
o="$tmp/out/level-dungeon"

"$GLTF_TRANSFORM" draco "$in" "$o.draco.glb" --quantize-position 14 >/dev/null
"$GLTFPACK" -i "$in" -o "$o.meshopt.glb" -cc -vp 14 >/dev/null
"$GLTFPACK" -i "$in" -o "$o.meshopt.gltf" -cc -vp 14 >/dev/null
"$GLTF_TRANSFORM" meshopt "$in" "$o.gt-meshopt.glb" --quantize-position 14 >/dev/null
"$GLTFPACK" -i "$in" -o "$o.quantized.glb" -vp 14 >/dev/null
"$GLTFPACK" -i "$in" -o "$o.quantized-norm.glb" -vp 14 -vpn >/dev/null
"$GLTF_TRANSFORM" quantize "$in" "$o.gt-quantized.glb" --quantize-position 14 >/dev/null

# Into place as a whole: an interrupted run leaves the previous variants or none.
rm -rf "$OUT.part"
mv "$tmp/out" "$OUT.part"
echo "$stamp" > "$OUT.part/STAMP"
rm -rf "$OUT"
mv "$OUT.part" "$OUT"
echo "make-gltf-variants: made $OUT:"
(cd "$OUT" && find . -type f ! -name STAMP -printf '  %p (%s bytes)\n' | sort)
