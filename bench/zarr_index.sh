#!/usr/bin/env bash
# Indexing an OME-Zarr where it lies (vdiso index) against reading its chunks and converting
# it, and views from the index against views from the converted store: the CT (Debian's
# invesalius-examples), the MRI (ch2better) and the generated head at 512^3, each written as an
# OME-Zarr 0.4 of blosc-lz4 chunks of CHUNK^3 by bench/make_scan_zarr.py (python3-zarr) into
# data/bench/zarr/. Local folders, in the page cache; whole processes, medians of RUNS. "Read every
# chunk" is cat of the chunk files (bytes only); "zarr-python" reads the array into memory with
# Debian's python3-zarr (fetch and decode every chunk, as a user's plain read does).
#
#   bench/zarr_index.sh [CHUNK] [RUNS]   (default 64 5)
set -euo pipefail
cd "$(dirname "$0")/.."
chunk=${1:-64}
runs=${2:-5}
vdiso=build/bin/vdiso
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p data/bench/zarr
[ -f data/bench/head512.raw ] || $vdiso synth data/bench/head512.raw --kind head --size 512 --quiet --force
printf 'NRRD0004\ntype: uint16\ndimension: 3\nsizes: 512 512 512\nspacings: 1 1 1\nencoding: raw\nendian: little\ndata file: head512.raw\n' \
  > data/bench/head512.nhdr

median() { sort -n | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
seconds() { local t0 t1; t0=$(date +%s.%N); "$@" > /dev/null; t1=$(date +%s.%N); python3 -c "print(round($t1 - $t0, 3))"; }
timed() { for _ in $(seq "$runs"); do seconds "$@"; done | median; }
ratio() { python3 -c "print(round($1 / $2, 2))"; }

echo "| scan | chunks | data MB | read every chunk s | zarr-python read s | index s | index / zarr-python | index, no levels s | convert s | index MB (% of data) | without levels MB (%) | SAGE normal: index / store s | octree: index / store s |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for spec in "cranium data/cranium.nhdr -423.5" "ch2better data/ch2better.nii.gz 40.5" "head512 data/bench/head512.nhdr 600.5"; do
  read -r name input iso <<< "$spec"
  zarr=data/bench/zarr/${name}_c$chunk.ome.zarr
  [ -d "$zarr" ] || /usr/bin/python3 bench/make_scan_zarr.py "$input" "$chunk" "$zarr" > /dev/null
  find "$zarr/0" -type f ! -name '.*' -exec cat {} + > /dev/null  # into the page cache
  bytes=$(find "$zarr/0" -type f ! -name '.*' -printf '%s\n' | awk '{s+=$1} END {print s}')
  chunks=$(find "$zarr/0" -type f ! -name '.*' | wc -l)
  read_s=$(timed sh -c "find $zarr/0 -type f ! -name '.*' -exec cat {} + > /dev/null")
  zarr_s=$(timed /usr/bin/python3 -c "import zarr; zarr.open('$zarr/0', 'r')[:]")
  index_s=$(timed $vdiso index "$zarr" --index "$work/i.vdiso" --quiet --force)
  index0_s=$(timed $vdiso index "$zarr" --index "$work/l0.vdiso" --levels 0 --quiet --force)
  convert_s=$(timed $vdiso convert "$zarr" "$work/s.vdiso" --quiet --force)
  index_b=$(stat -c %s "$work/i.vdiso")
  l0_b=$(stat -c %s "$work/l0.vdiso")
  sage_i=$(timed $vdiso extract "$work/i.vdiso" --iso "$iso" --method sage --stats -)
  sage_s=$(timed $vdiso extract "$work/s.vdiso" --iso "$iso" --method sage --stats -)
  oct_i=$(timed $vdiso extract "$work/i.vdiso" --iso "$iso" --method octree --stats -)
  oct_s=$(timed $vdiso extract "$work/s.vdiso" --iso "$iso" --method octree --stats -)
  printf "| %s | %s | %.1f | %s | %s | %s | %s | %s | %s | %.2f (%.1f%%) | %.3f (%.2f%%) | %s / %s | %s / %s |\n" \
    "$name" "$chunks" "$(python3 -c "print($bytes/1e6)")" "$read_s" "$zarr_s" "$index_s" "$(ratio "$index_s" "$zarr_s")" \
    "$index0_s" "$convert_s" \
    "$(python3 -c "print($index_b/1e6)")" "$(python3 -c "print(100*$index_b/$bytes)")" \
    "$(python3 -c "print($l0_b/1e6)")" "$(python3 -c "print(100*$l0_b/$bytes)")" "$sage_i" "$sage_s" "$oct_i" "$oct_s"
done
echo "(chunks of ${chunk}^3, blosc lz4; the folders in the page cache; medians of $runs; $(nproc) cores)"
