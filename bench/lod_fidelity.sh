#!/usr/bin/env bash
# Fidelity of the levels of detail on real scans and the generated head: SAGE at --lod-error 1
# against the full-resolution octree's picture, at 1x, 2.5x, 5x and 10x the normal distance
# and the closeup (`--view N`), 800 x 800, and what the levels save (bricks read against SAGE at
# full resolution, --lod-error 0).
#   covered kept   the reference's covered pixels the levels' picture covers (any colour)
#   agreement      those within 24/255 per channel (`vdiso compare`)
#   dark           pixels lit in the reference (brightest channel >= 80) drawn nearly black
#                  (covered, brightest channel < 40) in the levels' picture
# Data as bench/real_scans.sh (which makes the stores).
#
#   bench/lod_fidelity.sh
set -euo pipefail
cd "$(dirname "$0")/.."
vdiso=${BUILD_DIR:-build}/bin/vdiso
py=/usr/bin/python3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
stat() { "$py" -c "import json,sys; d=json.load(sys.stdin); print(d['$1'])"; }
echo "| scan | iso | view | covered kept | missing | other colour | agreement | dark | bricks (full res.) | coarse bricks |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for spec in "cranium -423.5" "cranium 200.5" "ch2better 40.5" "ch2 40.5" "head512 600.5" "head512 1224.5"; do
  set -- $spec
  store=data/bench/$1.vdiso iso=$2
  for view in 1 2.5 5 10 closeup; do
    common=(--iso "$iso" --view "$view" --size 800x800 --quiet --force)
    "$vdiso" extract "$store" "${common[@]}" --method octree --png "$tmp/ref.png"
    lod=$("$vdiso" extract "$store" "${common[@]}" --method sage --png "$tmp/lod.png" --stats -)
    full=$("$vdiso" extract "$store" "${common[@]}" --method sage --lod-error 0 --stats -)
    cmp=$("$vdiso" compare "$tmp/ref.png" "$tmp/lod.png")
    "$py" - "$1" "$iso" "$view" "$tmp/ref.png" "$tmp/lod.png" "$cmp" "$lod" "$full" <<'PY'
import json, re, sys
import numpy as np
from PIL import Image
scan, iso, view, ref, lod, cmp, lod_stats, full_stats = sys.argv[1:]
a = np.asarray(Image.open(ref).convert("RGB")).astype(int)
b = np.asarray(Image.open(lod).convert("RGB")).astype(int)
bg = a[0, 0]
lit = np.any(a != bg, axis=2) & (a.max(axis=2) >= 80)
drawn = np.any(b != bg, axis=2)
dark = int(np.sum(lit & drawn & (b.max(axis=2) < 40)))
m = re.match(r"agreement ([0-9.]+): (\d+) of (\d+) covered pixels \((\d+) missing, (\d+) of another colour", cmp)
agreement, same, covered, missing, other = float(m[1]), int(m[2]), int(m[3]), int(m[4]), int(m[5])
l, f = json.loads(lod_stats), json.loads(full_stats)
print(f"| {scan} | {iso} | {view} | {100 * (covered - missing) / covered:.2f} % of {covered} | {missing} | {other} | "
      f"{agreement:.4f} | {dark} | {l['bricks_loaded']} ({f['bricks_loaded']}) | {l['coarse_bricks']} |")
PY
  done
done
