#!/usr/bin/env bash
# Fetches the real-world test data into data/ (which is .gitignored):
#   data/castle/level/level-dungeon.gltf + .bin   (castle-game-engine-doc: creature_behaviors example)
#   data/cgal/elephant.off, data/cgal/armadillo.off (libcgal-demo: data.tar.gz)
#   data/openarena/pak6-patch088.pk3 (openarena-088-data: maps/oa_thor.bsp, ...)
#   data/openarena/pak1-maps.pk3     (openarena-081-maps: maps/q3dm6ish.bsp, maps/oa_dm1.bsp, ...)
#   data/castle/variants/            (Draco, meshopt, quantized copies of the dungeon: make-gltf-variants.sh)
# Debian packages are fetched with `apt-get download` into a cache folder (no root needed to
# download; `apt-get update` runs only when a download fails and we are root) and unpacked with
# `dpkg -x`/`dpkg-deb --fsys-tarfile`, taking only the files we need. Idempotent: files already in
# place are kept. Non-interactive (works in CI).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
DATA="${VISAUDIT_DATA_DIR:-$ROOT/data}"
CACHE="${VISAUDIT_CACHE_DIR:-$ROOT/.cache/debs}"
export DEBIAN_FRONTEND=noninteractive
mkdir -p "$DATA" "$CACHE"

# fetch_deb PACKAGE -> prints the path of PACKAGE's .deb in the cache, downloading it if needed.
fetch_deb() {
  local pkg="$1" deb
  deb="$(ls "$CACHE"/"${pkg}"_*.deb 2>/dev/null | head -n1 || true)"
  if [[ -z "$deb" ]]; then
    if ! (cd "$CACHE" && apt-get download "$pkg" >&2); then
      if [[ "$(id -u)" == 0 ]]; then
        echo "fetch-data: apt-get download $pkg failed; running apt-get update and retrying" >&2
        apt-get update -qq >&2
        (cd "$CACHE" && apt-get download "$pkg" >&2)
      else
        echo "fetch-data: apt-get download $pkg failed (run 'sudo apt-get update' and retry)" >&2
        return 1
      fi
    fi
    deb="$(ls "$CACHE"/"${pkg}"_*.deb | head -n1)"
  fi
  echo "$deb"
}

# 1. The dungeon level (glTF + its buffer; its textures are not needed: visaudit reads no images).
CASTLE_OUT="$DATA/castle/level"
CASTLE_SRC="usr/share/doc/castle-game-engine-doc/examples/creature_behaviors/data/level"
if [[ -s "$CASTLE_OUT/level-dungeon.gltf" && -s "$CASTLE_OUT/level-dungeon.bin" ]]; then
  echo "fetch-data: $CASTLE_OUT/level-dungeon.gltf already present"
else
  deb="$(fetch_deb castle-game-engine-doc)"
  tmp="$(mktemp -d)"
  trap 'rm -rf "$tmp"' EXIT
  dpkg-deb --fsys-tarfile "$deb" | tar -x -C "$tmp" "./$CASTLE_SRC/level-dungeon.gltf" "./$CASTLE_SRC/level-dungeon.bin"
  mkdir -p "$CASTLE_OUT"
  mv "$tmp/$CASTLE_SRC/level-dungeon.gltf" "$tmp/$CASTLE_SRC/level-dungeon.bin" "$CASTLE_OUT/"
  rm -rf "$tmp"
  trap - EXIT
  echo "fetch-data: fetched $CASTLE_OUT/level-dungeon.gltf and level-dungeon.bin from $(basename "$deb")"
fi

# 2. CGAL's elephant and armadillo (OFF), inside the data.tar.gz that libcgal-demo ships.
CGAL_OUT="$DATA/cgal"
if [[ -s "$CGAL_OUT/elephant.off" && -s "$CGAL_OUT/armadillo.off" ]]; then
  echo "fetch-data: $CGAL_OUT/elephant.off and armadillo.off already present"
else
  deb="$(fetch_deb libcgal-demo)"
  mkdir -p "$CGAL_OUT"
  dpkg-deb --fsys-tarfile "$deb" | tar -xO ./usr/share/doc/libcgal-dev/data.tar.gz |
    tar -xz -C "$CGAL_OUT" --strip-components=2 data/meshes/elephant.off data/meshes/armadillo.off
  echo "fetch-data: fetched $CGAL_OUT/elephant.off and armadillo.off from $(basename "$deb")"
fi

# 3. OpenArena maps (Quake 3 IBSP v46) in their .pk3 zip archives, as the game ships them: the
#    tests read maps/oa_thor.bsp from pak6 and maps/q3dm6ish.bsp and maps/oa_dm1.bsp from pak1
#    through the archive ("pak.pk3:maps/x.bsp"). Only the .pk3 is taken from each .deb.
OA_OUT="$DATA/openarena"
OA_SRC="usr/share/games/openarena/baseoa"
mkdir -p "$OA_OUT"
for pair in openarena-088-data:pak6-patch088.pk3 openarena-081-maps:pak1-maps.pk3; do
  pkg="${pair%%:*}" pk3="${pair#*:}"
  if [[ -s "$OA_OUT/$pk3" ]]; then
    echo "fetch-data: $OA_OUT/$pk3 already present"
    continue
  fi
  deb="$(fetch_deb "$pkg")"
  # Into a temporary name first, so an interrupted run never leaves a partial archive behind.
  dpkg-deb --fsys-tarfile "$deb" | tar -xO "./$OA_SRC/$pk3" > "$OA_OUT/$pk3.part"
  mv "$OA_OUT/$pk3.part" "$OA_OUT/$pk3"
  echo "fetch-data: fetched $OA_OUT/$pk3 from $(basename "$deb")"
done

# 4. Another loader's test corpus (issue 16's peer oracle): assimp-testmodels' OBJ/PLY/OFF/STL/glTF/GLB
#    files (with the .bin and textures they refer to), compared by tests/test_peer_corpus.cpp with
#    `assimp info` (assimp-utils, installed by scripts/install-deps.sh).
ASSIMP_OUT="$DATA/assimp"
if [[ -s "$ASSIMP_OUT/STAMP" ]]; then
  echo "fetch-data: $ASSIMP_OUT already present"
else
  deb="$(fetch_deb assimp-testmodels)"
  rm -rf "$ASSIMP_OUT.part" && mkdir -p "$ASSIMP_OUT.part"
  dpkg-deb --fsys-tarfile "$deb" | tar -x -C "$ASSIMP_OUT.part" --strip-components=4 ./usr/share/assimp/models
  basename "$deb" > "$ASSIMP_OUT.part/STAMP"
  rm -rf "$ASSIMP_OUT" && mv "$ASSIMP_OUT.part" "$ASSIMP_OUT"
  echo "fetch-data: fetched $ASSIMP_OUT from $(basename "$deb")"
fi

# 5. Draco, meshopt and quantized variants of the dungeon, made by real optimizers from the npm
#    registry (gltfpack, gltf-transform) at pinned versions: scripts/make-gltf-variants.sh.
bash "$ROOT/scripts/make-gltf-variants.sh"

echo "fetch-data: data in $DATA:"
(cd "$DATA" && find . -path ./assimp -prune -o -type f \( -name '*.gltf' -o -name '*.glb' -o -name '*.bin' -o -name '*.off' -o -name '*.pk3' \) -printf '  %p (%s bytes)\n' | sort)
