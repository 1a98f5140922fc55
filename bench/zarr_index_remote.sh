#!/usr/bin/env bash
# Views of an OME-Zarr in a bucket through a local index (vdiso index s3://...), against the
# store converted from it in the same bucket: bench/bucket_server.sh's endpoint (nginx behind the link by default) holding each answer's
# first byte DELAY_MS and capping bodies at 1 Gbit/s (bench/bucket_server.sh). The Zarr folders
# are bench/zarr_index.sh's (run it first), copied into data/bench/bucket/. Whole processes,
# medians of 5, 1024x1024 (vdiso extract's default camera).
#
#   bench/zarr_index_remote.sh [DELAY_MS]   (default 20)
set -euo pipefail
cd "$(dirname "$0")/.."
delay=${1:-20}
v=build/bin/vdiso
mkdir -p data/bench/bucket
for n in head512 cranium; do
  [ -d "data/bench/bucket/${n}_c64.ome.zarr" ] || cp -r "data/bench/zarr/${n}_c64.ome.zarr" data/bench/bucket/
  [ -f "data/bench/bucket/${n}_z.vdiso" ] || $v convert "data/bench/bucket/${n}_c64.ome.zarr" "data/bench/bucket/${n}_z.vdiso" --quiet
done
source bench/bucket_server.sh
start_bucket_server "$delay" 1000
median() { sort -n | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
seconds() { local t0 t1; t0=$(date +%s.%N); "$@" > /dev/null; t1=$(date +%s.%N); python3 -c "print(round($t1 - $t0, 3))"; }
timed() { for _ in 1 2 3 4 5; do seconds "$@"; done | median; }
echo "| data | index from s3:// s | SAGE normal: index + s3:// Zarr s | SAGE: s3:// store s | octree: index + Zarr s | octree: store s | SAGE chunk MB read of data MB |"
echo "|---|---|---|---|---|---|---|"
for spec in "head512 600.5" "cranium -423.5"; do
  read -r n iso <<< "$spec"
  index_s=$(timed $v index "s3://bucket/${n}_c64.ome.zarr" --index "$work/$n.vdiso" "${remote[@]}" --quiet --force)
  si=$(timed $v extract "$work/$n.vdiso" --iso "$iso" --method sage "${remote[@]}" --stats -)
  ss=$(timed $v extract "s3://bucket/${n}_z.vdiso" --iso "$iso" --method sage "${remote[@]}" --stats -)
  oi=$(timed $v extract "$work/$n.vdiso" --iso "$iso" --method octree "${remote[@]}" --stats -)
  os=$(timed $v extract "s3://bucket/${n}_z.vdiso" --iso "$iso" --method octree "${remote[@]}" --stats -)
  $v extract "$work/$n.vdiso" --iso "$iso" --method sage "${remote[@]}" --stats "$work/$n.json" > /dev/null
  read_mb=$(python3 -c "import json; print(round(json.load(open('$work/$n.json'))['chunk_bytes_read'] / 1e6, 1))")
  data_mb=$(python3 -c "print(round($(du -sb "data/bench/bucket/${n}_c64.ome.zarr" | cut -f1) / 1e6, 1))")
  echo "| $n | $index_s | $si | $ss | $oi | $os | $read_mb of $data_mb |"
done
echo "(${delay} ms before each first byte, 1 Gbit/s; medians of 5; $(nproc) cores)"
