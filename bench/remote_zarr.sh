#!/usr/bin/env bash
# Converting an OME-Zarr from object storage: a generated head written as OME-Zarr 0.4 (zlib
# chunks of CHUNK^3, bench/make_ome_zarr.py) in data/bench/bucket/, converted from the local
# folder and from s3:// through bench/bucket_server.sh's endpoint (nginx behind the link by default) holding each request's first byte for
# DELAY_MS (a public bucket: the server's signature check does not count), against downloading
# the chunks first at 1 Gbit/s. Medians of RUNS.
#
#   bench/remote_zarr.sh [SIZE] [DELAY_MS] [CHUNK] [RUNS]   (default 512 20 64 3)
set -euo pipefail
cd "$(dirname "$0")/.."
size=${1:-512}
delay=${2:-20}
chunk=${3:-64}
runs=${4:-3}
vdiso=build/bin/vdiso
mkdir -p data/bench/bucket
name=head${size}_c${chunk}.ome.zarr
zarr=data/bench/bucket/$name
if [ ! -d "$zarr" ]; then
  $vdiso synth "data/bench/head$size.raw" --kind head --size "$size" --quiet --force
  bench/make_ome_zarr.py "data/bench/head$size.raw" "$size" "$size" "$size" "$chunk" "$zarr"
  rm -f "data/bench/head$size.raw"
fi
source bench/bucket_server.sh
start_bucket_server "$delay" 0

median() { sort -n | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
seconds() { local t0 t1; t0=$(date +%s.%N); "$@" > /dev/null; t1=$(date +%s.%N); python3 -c "print(round($t1 - $t0, 2))"; }
local_s=$(for _ in $(seq "$runs"); do seconds $vdiso convert "$zarr" "$work/local.vdiso" --quiet --force; done | median)
remote_s=$(for _ in $(seq "$runs"); do seconds $vdiso convert "s3://bucket/$name" "$work/remote.vdiso" "${remote[@]}" --quiet --force; done | median)
cmp "$work/local.vdiso" "$work/remote.vdiso"
bytes=$(du -sb "$zarr" | cut -f1)
chunks=$(find "$zarr/0" -type f ! -name '.*' | wc -l)
# Downloading first: a request per chunk, 32 at a time, one delay each, and the bytes at 1 Gbit/s.
download=$(python3 -c "print(round($bytes / 125e6 + ($chunks + 31) // 32 * $delay / 1000, 2))")
echo "| input | chunks | MB | local folder s | s3:// through ${delay} ms s | download at 1 Gbit/s s |"
echo "|---|---|---|---|---|---|"
printf "| %s | %s | %.1f | %s | %s | %s |\n" "$name" "$chunks" "$(python3 -c "print($bytes/1e6)")" "$local_s" "$remote_s" "$download"
echo "(medians of $runs; the stores written are byte for byte the same; $(nproc) cores; the folder in the page cache)"
