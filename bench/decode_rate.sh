#!/usr/bin/env bash
# Brick decoding per core on real scans and the generated head (issue: fast and faithful on
# real scans): the cache's decode time (checksum, LZ4, unshuffle: BrickCache's decodeSeconds)
# of a full extraction on 1 thread with no read-ahead, so every brick is decoded on the
# extraction's own thread, over the bricks' stored samples (35^3 each, ghosts included).
# Median, least and most of RUNS fresh processes; the store in the page cache.
#
#   bench/decode_rate.sh [RUNS]      default 11; stores as bench/real_scans.sh makes them
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-11}
vdiso=${BUILD_DIR:-build}/bin/vdiso
echo "| scan | sample bytes | bricks | decode GB/s of samples, median (least-most) |"
echo "|---|---|---|---|"
for spec in "cranium 200.5 2" "ch2better 40.5 1" "ch2 40.5 1" "head512 600.5 2"; do
  set -- $spec
  for _ in $(seq "$runs"); do
    "$vdiso" extract "data/bench/$1.vdiso" --iso "$2" --method octree --threads 1 --prefetch 0 --quiet --stats -
  done | /usr/bin/python3 -c "
import json, statistics, sys
runs = [json.loads(line) for line in sys.stdin]
rates = [r['bricks_loaded'] * 35**3 * $3 / r['decode_s'] / 1e9 for r in runs]
print(f\"| $1 | $3 | {runs[0]['bricks_loaded']} | {statistics.median(rates):.2f} ({min(rates):.2f}-{max(rates):.2f}) |\")"
done
