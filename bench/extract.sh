#!/usr/bin/env bash
# Full extraction through `vdiso extract`: octree and noise, 1 and 2 threads, median of RUNS,
# on the 512^3 generated head (skin 600.5, bone 1224.5) and the real MRI (iso 40.5).
# Page cache warm (the store is read once before timing): this isolates extraction; the I/O
# tables of the out-of-core issue measure cold reads.
#
#   bench/extract.sh [RUNS]      default 3
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-3}
vdiso=build/bin/vdiso
[ -x $vdiso ] || scripts/build.sh
mkdir -p data
[ -f data/head512.vdiso ] || $vdiso synth data/head512.vdiso --kind head --size 512 --quiet
if [ ! -f data/ch2better.vdiso ]; then
  scripts/fetch_data.sh
  $vdiso convert data/ch2better.nii.gz data/ch2better.vdiso --quiet
fi

echo "| volume | iso | method | threads | runs | median extract s | Mvoxels/s | preprocess s | triangles | bricks read | MB read | peak RSS MB |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
case_row() {  # store iso method threads
  local out=()
  for _ in $(seq "$runs"); do
    out+=("$($vdiso extract "$1" --iso "$2" --method "$3" --threads "$4" --stats - --quiet)")
  done
  printf '%s\n' "${out[@]}" | python3 -c '
import json, statistics, sys
rows = [json.loads(l) for l in sys.stdin if l.strip()]
med = statistics.median(r["extract_s"] for r in rows)
r = rows[0]
vox = r["voxels_per_s"] * r["extract_s"]
print("| %s | %g | %s | %d | %d | %.3f | %.0f | %.2f | %d | %d | %.1f | %.0f |" % (
    r["file"].split("/")[-1], r["iso"], r["method"], r["threads"], len(rows), med,
    vox / med / 1e6, statistics.median(x["preprocess_s"] for x in rows), r["triangles"],
    r["bricks_loaded"], r["bytes_read"] / 1e6, max(x["peak_rss_mb"] for x in rows)))'
}
for spec in "data/head512.vdiso 600.5" "data/head512.vdiso 1224.5" "data/ch2better.vdiso 40.5"; do
  set -- $spec
  cat "$1" > /dev/null  # warm the page cache
  for method in octree noise; do
    for threads in 1 2; do
      case_row "$1" "$2" "$method" "$threads"
    done
  done
done
