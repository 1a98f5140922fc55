#!/usr/bin/env bash
# Conversion throughput and peak memory of each reader on a 1024^3-class volume, cold input,
# median of N runs, the raw baseline in the same run.
#
#   bench/readers.sh [RUNS]      default 3
#
# Writes the inputs into data/bench_inputs/ if missing (vdiso_bench_inputs, from
# data/head1024.raw, which `vdiso synth` writes if it is missing too: about 6 GB in all), then
# converts each RUNS times into data/bench_inputs/out.vdiso, dropping the page cache before each
# run (root only; otherwise the input is warm and the table says so). Rounds alternate the
# inputs (raw, DICOM, ..., raw, DICOM, ...) so a busy minute on this shared machine falls on all
# rows alike. Prints a Markdown table; bench/log.md records one. The store is deleted at the end.
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-3}
vdiso=build/bin/vdiso
gen=build/bin/vdiso_bench_inputs
if [ ! -x $vdiso ] || [ ! -x $gen ]; then scripts/build.sh; fi
mkdir -p data/bench_inputs
raw=data/head1024.raw
in=data/bench_inputs
out=$in/out.vdiso
[ -f $raw ] || nice -n 19 $vdiso synth $raw --kind head --size 1024 --quiet
nice -n 19 $gen $in --raw $raw >&2

# drop (the page cache) and measure (seconds, peak KB; for vdiso with a GDCM or libhdf5 helper,
# the larger of the two processes).
. bench/cold_run.sh

# Runs "$@" once, untimed, sampling every 0.1 s the resident memory of vdiso and its helper
# processes together; prints the largest sum in KB. (Their shared library pages count twice:
# a few MB.)
tree_peak() {
  "$@" > /dev/null &
  local pid=$! peak=0 kb
  while kill -0 $pid 2> /dev/null; do
    kb=$(ps -o rss= -p $pid --ppid $pid | awk '{ s += $1 } END { print s + 0 }')
    [ "$kb" -gt "$peak" ] && peak=$kb
    sleep 0.1
  done
  wait $pid
  echo "$peak"
}

# The rows: label, what `vdiso convert` is given, samples in bytes (as converted), extra options.
# helpers: 1 when the reader runs in a helper process (GDCM, libhdf5), whose memory /usr/bin/time
# does not add to vdiso's.
labels=() inputs=() samples=() extras=() helpers=()
add() { labels+=("$1"); inputs+=("$2"); samples+=("$3"); helpers+=("$4"); extras+=("${5:-}"); }
full=$((1024 * 1024 * 1024 * 2))
add "raw u16 (baseline)" $raw $full 0 "--dims 1024,1024,1024 --type u16"
add "DICOM, 1000 files, Explicit VR LE" $in/dicom $((512 * 512 * 1000 * 2)) 1
add "DICOM, 1000 files, JPEG Lossless" $in/dicom_jpegll $((512 * 512 * 1000 * 2)) 1
add "TIFF, 1024 pages, uncompressed" $in/head.tif $full 0
add "TIFF, 1024 pages, deflate + predictor" $in/head_deflate.tif $full 0
add "OME-Zarr v2, 64^3 chunks, blosc lz4 + shuffle" $in/head.ome.zarr $full 0
add "HDF5, 64^3 chunks, shuffle + deflate 1" $in/head.h5:/volume $full 1
if [ -e $in/head_contig.h5 ]; then
  add "HDF5, contiguous, uncompressed" $in/head_contig.h5:/volume $full 1
fi

declare -A results
echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)" >&2
for r in $(seq "$runs"); do
  for i in "${!labels[@]}"; do
    drop
    # shellcheck disable=SC2086  # extras are words
    results[$i]+="$(measure $vdiso convert "${inputs[$i]}" $out --force ${extras[$i]})"$'\n'
  done
  echo "round $r done, load $(cut -d' ' -f1-3 /proc/loadavg)" >&2
done
declare -A together
for i in "${!labels[@]}"; do
  if [ "${helpers[$i]}" = 1 ]; then
    drop
    # shellcheck disable=SC2086
    together[$i]=$(tree_peak $vdiso convert "${inputs[$i]}" $out --force ${extras[$i]})
  fi
done
rm -f $out

echo "| format | input on disk (samples) | runs | median s | runs s | MB/s of samples | peak RSS MB | peak / samples | vdiso + helper MB |"
echo "|---|---|---|---|---|---|---|---|---|"
for i in "${!labels[@]}"; do
  disk=$(du -sbL "${inputs[$i]%%:/*}" | cut -f1)
  printf '%s' "${results[$i]}" | sort -n | awk -v label="${labels[$i]}" -v d="$disk" \
      -v b="${samples[$i]}" -v cold="$cold" -v both="${together[$i]:-}" '
    { s[NR]=$1; if ($2 > peak) peak = $2 } END {
      med = s[int((NR+1)/2)];
      printf "| %s | %.0f MB %s (%.0f MB) | %d | %.2f | %.1f-%.1f | %.0f | %.0f | %.1f%% | %s |\n",
        label, d/1e6, cold, b/1e6, NR, med, s[1], s[NR], b/1e6/med, peak/1024, 100*peak*1024/b,
        both == "" ? "-" : sprintf("%.0f", both/1024) }'
done
