#!/usr/bin/env bash
# vdiso index of an OME-Zarr that has its own scales: the index that takes scale 1 as its level 1
# (the default; levels 2 on filtered from it and kept in the index), the one that takes every
# scale that fits (--scale-levels 16), and the one that filters and stores every level
# (--own-levels), against zarr-python reading every chunk. The generated head at N^3 u16, written by
# vdiso_bench_inputs as OME-Zarr 0.4 with SCALES levels (a nearest-neighbour pyramid: level l is
# every 2^l-th sample), blosc-lz4 chunks of CHUNK^3, into data/bench/z${N}s/ (made when missing).
# Local, the folder in the page cache; whole processes on all cores, alternated, median of RUNS:
#   zarr-python: level 0's chunks, then every scale's (a layer of chunks at a time);
#   vdiso index, each way: time, and the index's size against the data;
#   the first SAGE normal and distant views from each index (extract_s, chunks read);
# then, unless SKIP_REMOTE=1, the same folder in the bucket (bench/bucket_server.sh's endpoint,
# DELAY_MS before each first byte, 1 Gbit/s): both indexes made from s3:// into local files,
# one run each, and the first SAGE normal view from each, whole process, with its chunk bytes.
# SKIP_LOCAL=1 runs the bucket's part only.
#
#   bench/zarr_index_scales.sh [N] [CHUNK] [SCALES] [RUNS] [ISO] [DELAY_MS]
#   (default 2048 128 4 3 600.5 20)
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-2048}
chunk=${2:-128}
scales=${3:-4}
runs=${4:-3}
iso=${5:-600.5}
delay=${6:-20}
v=build/bin/vdiso
dir=data/bench/z${n}s
zarr=$dir/head.ome.zarr
mkdir -p "$dir"
[ -d "$zarr" ] || build/bin/vdiso_bench_inputs "$dir" --synth "$n" --only zarr --chunk "$chunk" --scales "$scales"
bytes() { find "$@" -type f ! -name '.*' -printf '%s\n' | awk '{s+=$1} END {print s}'; }
data0=$(bytes "$zarr/0")
data=$(bytes "$zarr")
echo "data: $zarr, level 0 $(python3 -c "print(round($data0 / 1e9, 2))") GB, all $scales scales $(python3 -c "print(round($data / 1e9, 2))") GB"
find "$zarr" -type f -exec cat {} + > /dev/null  # into the page cache
seconds() { local t0 t1; t0=$(date +%s.%N); "$@" > /dev/null; t1=$(date +%s.%N); python3 -c "print(round($t1 - $t0, 2))"; }
zarr_read() {  # the arrays named, every chunk, a layer of chunks at a time
  /usr/bin/python3 -c "
import sys, zarr
for path in sys.argv[1:]:
    a = zarr.open(path, 'r')
    for z in range(0, a.shape[0], a.chunks[0]):
        a[z:z + a.chunks[0]]" "$@"
}
all_scales=()
for ((l = 0; l < scales; ++l)); do all_scales+=("$zarr/$l"); done
if [ -z "${SKIP_LOCAL:-}" ]; then
declare -A t
for ((r = 0; r < runs; ++r)); do
  t[zarr0]+="$(seconds zarr_read "$zarr/0") "
  t[zarrall]+="$(seconds zarr_read "${all_scales[@]}") "
  t[one]+="$(seconds $v index "$zarr" --index "$dir/one.vdiso" --quiet --force) "
  t[own]+="$(seconds $v index "$zarr" --index "$dir/own.vdiso" --scale-levels 16 --quiet --force) "
  t[made]+="$(seconds $v index "$zarr" --index "$dir/made.vdiso" --own-levels --quiet --force) "
done
median() { python3 -c "import statistics, sys; v = [float(x) for x in sys.argv[1:]]; print('%.2f (%s)' % (statistics.median(v), ', '.join('%.2f' % x for x in v)))" $1; }
echo "zarr-python reads level 0: $(median "${t[zarr0]}") s"
echo "zarr-python reads every scale: $(median "${t[zarrall]}") s"
for k in one own made; do
  size=$(stat -c %s "$dir/$k.vdiso")
  echo "vdiso index ($k levels): $(median "${t[$k]}") s; index $(python3 -c "print('%.2f MB, %.3f%% of the data' % ($size / 1e6, 100 * $size / $data))")"
  for view in normal distant; do
    $v extract "$dir/$k.vdiso" --iso "$iso" --method sage --view "$view" --stats - --quiet | python3 -c "
import json, sys
j = json.loads(sys.stdin.read())
print('  SAGE $view view: extract %.3f s, %d triangles, %d chunks (%.1f MB) read, %d coarse bricks'
      % (j['extract_s'], j['triangles'], j.get('chunks_read', 0), j.get('chunk_bytes_read', 0) / 1e6, j.get('coarse_bricks', 0)))"
  done
done
fi
if [ -z "${SKIP_REMOTE:-}" ]; then
  ln -sfn "$(realpath "$zarr")" "data/bench/bucket/head${n}s.ome.zarr"
  source bench/bucket_server.sh
  start_bucket_server "$delay" 1000
  url=s3://bucket/head${n}s.ome.zarr
  for k in one own made; do
    extra=()
    [ $k = own ] && extra=(--scale-levels 16)
    [ $k = made ] && extra=(--own-levels)
    echo "vdiso index from $url ($k levels): $(seconds $v index "$url" --index "$dir/remote_$k.vdiso" "${extra[@]}" "${remote[@]}" --quiet --force) s"
    echo "  SAGE normal view, index + s3:// chunks, whole process: $(seconds $v extract "$dir/remote_$k.vdiso" --iso "$iso" --method sage "${remote[@]}" --stats "$work/$k.json") s, \
$(python3 -c "import json; j = json.load(open('$work/$k.json')); print('%d chunks, %.1f MB, %d requests' % (j.get('chunks_read', 0), j.get('chunk_bytes_read', 0) / 1e6, j.get('chunk_requests', 0)))")"
  done
  echo "(against $endpoint)"
fi
echo "(${n}^3 u16, $scales scales, chunks of ${chunk}^3; $(nproc) cores; $(date -u +%F) at $(git rev-parse --short HEAD))"
