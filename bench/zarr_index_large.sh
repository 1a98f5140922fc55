#!/usr/bin/env bash
# vdiso index on a large OME-Zarr, local and in a bucket: the generated head at N^3 u16 written
# by vdiso_bench_inputs (OME-Zarr 0.4, one scale, blosc-lz4 chunks of CHUNK^3) into
# data/bench/bucket/headN.ome.zarr (made when missing), indexes in data/bench/zN/. Whole
# processes, one run each (each is long); SKIP_LOCAL=1 runs the bucket's part only:
#   local, page cache warm: a plain read of every chunk (zarr-python, a layer of chunks at a time,
#     so that memory stays a layer), the index pass, the index's size, the first SAGE normal view
#     from the index, and vdiso convert then the same view;
#   through bench/bucket_server.sh's endpoint at DELAY_MS before each first byte and 1 Gbit/s
#     (bench/bucket_server.sh; the same folder, in the bucket): the index pass, the
#     first SAGE normal and distant views from the local index with the chunks at s3://, and
#     vdiso serve's first frames (vdiso_serve_bench, a fresh server and client, no warm-up).
#
#   bench/zarr_index_large.sh [N] [CHUNK] [DELAY_MS] [ISO]   (default 2048 128 20 600.5)
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-2048}
chunk=${2:-128}
delay=${3:-20}
iso=${4:-600.5}
v=build/bin/vdiso
dir=data/bench/z$n
zarr=data/bench/bucket/head$n.ome.zarr
mkdir -p "$dir" data/bench/bucket
if [ ! -d "$zarr" ]; then
  build/bin/vdiso_bench_inputs "$dir" --synth "$n" --only zarr --chunk "$chunk"
  mv "$dir/head.ome.zarr" "$zarr"
fi
seconds() { local t0 t1; t0=$(date +%s.%N); "$@" > /dev/null; t1=$(date +%s.%N); python3 -c "print(round($t1 - $t0, 2))"; }
data_b=$(find "$zarr/0" -type f ! -name '.*' -printf '%s\n' | awk '{s+=$1} END {print s}')
echo "data: $zarr, $(find "$zarr/0" -type f ! -name '.*' | wc -l) chunks, $(python3 -c "print(round($data_b / 1e9, 2))") GB"
find "$zarr/0" -type f ! -name '.*' -exec cat {} + > /dev/null  # into the page cache
if [ -z "${SKIP_LOCAL:-}" ]; then
echo "cat every chunk: $(seconds sh -c "find $zarr/0 -type f ! -name '.*' -exec cat {} + > /dev/null") s"
echo "zarr-python reads every chunk (a layer at a time): $(seconds /usr/bin/python3 -c "
import zarr
a = zarr.open('$zarr/0', 'r')
for z in range(0, a.shape[0], a.chunks[0]):
    a[z:z + a.chunks[0]]") s"
echo "vdiso index: $(seconds $v index "$zarr" --index "$dir/local.vdiso" --quiet --force) s, \
$(python3 -c "import os; b = os.path.getsize('$dir/local.vdiso'); print('%.1f MB, %.2f%% of the data' % (b / 1e6, 100 * b / $data_b))")"
echo "SAGE normal view from the index: $(seconds $v extract "$dir/local.vdiso" --iso "$iso" --method sage --stats -) s"
echo "vdiso convert: $(seconds $v convert "$zarr" "$dir/converted.vdiso" --quiet --force) s; \
then the view: $(seconds $v extract "$dir/converted.vdiso" --iso "$iso" --method sage --stats -) s"
rm -f "$dir/converted.vdiso"
fi

source bench/bucket_server.sh
start_bucket_server "$delay" 1000
url=s3://bucket/head$n.ome.zarr
echo "vdiso index from $url: $(seconds $v index "$url" --index "$dir/remote.vdiso" "${remote[@]}" --quiet --force) s"
for view in normal distant; do
  $v extract "$dir/remote.vdiso" --iso "$iso" --method sage --view "$view" "${remote[@]}" --stats "$work/$view.json" > /dev/null
  python3 - "$work/$view.json" "$view" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
print("SAGE %s view, index + %s chunks: extract %.2f s, %d chunks, %.1f MB of them, %d requests, %d triangles"
      % (sys.argv[2], "remote", j["extract_s"], j.get("chunks_read", 0), j.get("chunk_bytes_read", 0) / 1e6,
         j.get("chunk_requests", 0), j["triangles"]))
PY
  echo "  whole process: $(seconds $v extract "$dir/remote.vdiso" --iso "$iso" --method sage --view "$view" "${remote[@]}" --stats -) s"
done
build/bin/vdiso_serve_bench "$dir/remote.vdiso" --iso "$iso" --frames 2 --size 1024 --no-warmup --web web \
  "${remote[@]}" > "$work/frames.json"
python3 - "$work/frames.json" <<'PY'
import json, sys
for line in open(sys.argv[1]):
    j = json.loads(line)
    if not j.get("summary"):
        print("vdiso serve frame %d: coarse frame complete %.0f ms, first geometry %.0f ms, complete %.0f ms, %d triangles"
              % (j["frame"], j["client_coarse_complete_ms"], j["client_first_geometry_ms"], j["client_complete_ms"],
                 j["triangles"]))
PY
echo "(${n}^3 u16, chunks of ${chunk}^3; ${delay} ms before each first byte, 1 Gbit/s; $(nproc) cores; $(date -u +%F))"
