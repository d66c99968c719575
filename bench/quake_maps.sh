#!/usr/bin/env bash
# Issue 15's floors on every Quake 3 map of the project's data (both OpenArena packs): per map the
# spawn views' false-cull and beyond-the-far-plane pixels of the cells (PVS) stage, the cross-check's
# genuine disagreements (best 0), the views with false culls and those without evidence (must be 0).
#   bash bench/quake_maps.sh [WIDTH HEIGHT]      (default 160 90; about 10 minutes on 2 cores)
# Never run by the tests. Needs build/visaudit and data/openarena (scripts/fetch-data.sh).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
W="${1:-160}" H="${2:-90}"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
for pk in pak1-maps pak6-patch088; do
  for m in $(python3 -c "import zipfile,sys; print(' '.join(n for n in zipfile.ZipFile(sys.argv[1]).namelist() if n.endswith('.bsp')))" "$ROOT/data/openarena/$pk.pk3"); do
    name="$pk-$(basename "$m" .bsp)"
    "$ROOT/build/visaudit" analyze "$ROOT/data/openarena/$pk.pk3:$m" --views spawns --width "$W" --height "$H" \
      --no-ordering --no-zfight --out "$WORK/$name" --quiet 2> "$WORK/$name.err" > /dev/null || echo "$name: exit $? ($(head -c 200 "$WORK/$name.err"))"
  done
done
python3 - "$WORK" <<'PY'
import glob, json, os, sys
print('%-32s %7s %5s %9s %9s %7s %6s %8s' % ('map', 'tris', 'views', 'false px', 'beyond px', 'genuine', 'views', 'no evid'))
tot = [0] * 6
for d in sorted(glob.glob(sys.argv[1] + '/*/')):
    r = json.load(open(d + 'report.json'))
    fc = bf = gen = fcv = miss = 0
    for v in r['views']:
        a = v.get('audit', {})
        c = a.get('false_culls', {}).get('by_stage', {}).get('cells', {})
        f = c.get('false_cull_pixels', 0)
        fc += f
        bf += c.get('beyond_far_plane_pixels', 0)
        gen += v.get('raycast', {}).get('cross_check', {}).get('genuine', 0)
        pe = a.get('pvs_evidence') or {}
        if f:
            fcv += 1
            miss += not pe.get('objects') or pe.get('false_cull_pixels') != f
    row = (r['scene']['triangles'], len(r['views']), fc, bf, gen, fcv)
    tot = [t + x for t, x in zip(tot, row)]
    print('%-32s %7d %5d %9d %9d %7d %6d %8d' % ((os.path.basename(d[:-1]),) + row + (miss,)))
print('%-32s %7d %5d %9d %9d %7d %6d' % (('all',) + tuple(tot)))
PY
