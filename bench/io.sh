#!/usr/bin/env bash
# I/O against extraction, cold (the out-of-core issue's tables): for each view and isovalue,
# the bytes sage, wise and octree read from a store whose pages were dropped (--cold: O_DIRECT
# reads), against the bytes of all active bricks; I/O and decode seconds against extraction;
# and, in the same run, what a user would spend instead: reading the raw volume whole from
# cold disk and running VTK Flying Edges on 2 threads (bench/raw_baseline.cpp, needs
# libvtk9-dev; built in build-vtk).
#
#   bench/io.sh [SIZE]     default 1024 (needs data/headSIZE.raw; generated if missing)
set -euo pipefail
cd "$(dirname "$0")/.."
size=${1:-1024}
raw=data/head$size.raw
store=data/head$size.vdiso
bench/build_vtk.sh vdiso vdiso_raw_baseline
vdiso=build-vtk/bin/vdiso
mkdir -p data
[ -f $raw ] || $vdiso synth $raw --kind head --size $size --quiet
[ -f $store ] || $vdiso convert $raw $store --dims $size,$size,$size --type u16 --quiet
store_mb=$(python3 -c "import os; print(round(os.path.getsize('$store') / 1e6, 1))")

echo "Store: $store, $store_mb MB. Cold reads (O_DIRECT), page cache dropped before each run."
echo
echo "io s and decode s run on the reader threads, ahead of the extraction (summed over them);"
echo "wait s is the part the extraction waited for (summed over strips for sage x2)."
echo
echo "| iso | view | method | wall s | extract s | io s | decode s | wait s | bricks read | MB read | % of store | active bricks MB | triangles | points |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for iso in 600.5 1224.5; do
  active=$($vdiso info $store --iso $iso --json | python3 -c 'import json,sys; print(round(json.load(sys.stdin)["active_bytes"] / 1e6, 1))')
  for view in distant normal closeup; do
    for method in octree wise sage "sage x2"; do
      sync
      start=$(date +%s.%N)
      # The full methods take no camera (without a picture to frame): their rows repeat per view.
      # "sage x2": 2 threads (image strips), as the baseline's Flying Edges has.
      stats=$($vdiso extract $store --iso $iso --method ${method%% *} --cold --stats - --quiet \
              $( [ "$method" != octree ] && echo --view $view ) \
              $( [ "$method" = "sage x2" ] && echo --threads 2 ))
      wall=$(python3 -c "print(round($(date +%s.%N) - $start, 3))")
      python3 -c '
import json, sys
d = json.loads(sys.argv[1])
print("| %s | %s | %s | %s | %.3f | %.3f | %.3f | %.3f | %d | %.1f | %.1f%% | %s | %d | %d |" % (
    sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5], d["extract_s"], d["io_s"], d["decode_s"],
    d["brick_wait_s"], d["bricks_loaded"], d["bytes_read"] / 1e6,
    100 * d["bytes_read"] / 1e6 / float(sys.argv[6]),
    sys.argv[7], d["triangles"], d["points"]))' "$stats" $iso $view "$method" $wall $store_mb $active
    done
  done
done

echo
echo "Bricks SAGE reads against the bricks that hold visible surface (--oracle, 800x800; the"
echo "same run warm, so that the oracle's full extraction and rendering stay out of the times):"
echo
echo "| iso | view | bricks read | of which read ahead, then hidden | culled by sub-blocks | oracle bricks | read / oracle |"
echo "|---|---|---|---|---|---|---|"
for iso in 600.5 1224.5; do
  for view in distant normal closeup; do
    $vdiso extract $store --iso $iso --method sage --view $view --oracle --stats - --quiet |
      python3 -c '
import json, sys
d = json.load(sys.stdin)
print("| %s | %s | %d | %d | %d | %d | %.2f |" % (sys.argv[1], sys.argv[2], d["bricks_loaded"],
      d["bricks_prefetched_unused"], d["bricks_culled_by_sub_blocks"], d["oracle_bricks"],
      d["bricks_over_oracle"]))' $iso $view
  done
done

echo
echo "What a user would spend instead (read the raw volume whole, cold, then VTK Flying Edges):"
echo
for iso in 600.5 1224.5; do
  status=0
  build-vtk/bin/vdiso_raw_baseline $raw --dims $size,$size,$size --type u16 --iso $iso \
    --threads 2 2>/tmp/vdiso_baseline.err || status=$?
  if [ $status -ne 0 ]; then
    echo "Flying Edges did not finish (exit status $status; 137: killed for lack of memory, the"
    echo "volume plus a byte of scratch per voxel exceeding this machine's RAM), after reading:"
    grep read_s /tmp/vdiso_baseline.err || true
  fi
done
rm -f /tmp/vdiso_baseline.err

echo
echo "A moving camera: sage, normal view orbit of 8 frames, one cache, cold first frame:"
echo
echo "| frame | extract s | io s | bricks read | MB read | triangles |"
echo "|---|---|---|---|---|---|"
$vdiso extract $store --iso 600.5 --method sage --view normal --path orbit:8 --cold --stats - --quiet |
  python3 -c '
import json, sys
for line in sys.stdin:
    d = json.loads(line)
    print("| %d | %.3f | %.3f | %d | %.1f | %d |" % (d["frame"], d["extract_s"], d["io_s"],
          d["bricks_loaded"], d["bytes_read"] / 1e6, d["triangles"]))'
