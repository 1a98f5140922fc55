#!/usr/bin/env bash
# vdiso.marching_cubes against scikit-image and VTK's Flying Edges, all from Python, in one run:
# seconds (median of 3; scikit-image once) and peak memory above the loaded input, 1 thread and
# all cores, on the real MRI and a generated 512^3 head. Prints a Markdown table.
#   bench/python.sh            (after scripts/build.sh; the data comes from scripts/fetch_data.sh)
#   bench/python.sh lazy [N]   instead: an N^3 (default 2048) Dask array generated lazily, converted
#                              and its SAGE normal view extracted from Python: seconds, peak RSS
#                              (bench/python_lazy.py; the store goes to data/bench/lazyN.vdiso)
#   bench/python.sh dask [N] [C]  instead: marching_cubes on an N^3 (default 1024) u16 Dask array
#                              of C^3 (default 64) chunks generated lazily, read a layer at a
#                              time, against computing it whole first, and on a local cluster of
#                              1 and 2 worker processes (bench/python_dask_mc.py)
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh bench
build=${BUILD_DIR:-build}
py="env PYTHONPATH=$build/python /usr/bin/python3"
mkdir -p data/bench
#   bench/python.sh scans [R]  instead: the real scans in memory, as a Zarr array loaded first, and
#                              read a layer at a time as Zarr and Dask (bench/python_scans_mc.py)
if [ "${1:-}" = scans ]; then
  [ -f data/ch2better.nii.gz ] || scripts/fetch_data.sh
  PYTHONPATH=$build/python:bench /usr/bin/python3 bench/python_scans_mc.py "${2:-5}"
  exit 0
fi
#   bench/python.sh skimage [R]  instead: vdiso.marching_cubes against scikit-image's on the real
#                              scans, surface, normals, winding, time (bench/python_vs_skimage.py)
if [ "${1:-}" = skimage ]; then
  [ -f data/ch2better.nii.gz ] || scripts/fetch_data.sh
  PYTHONPATH=$build/python:bench /usr/bin/python3 bench/python_vs_skimage.py "${2:-3}"
  exit 0
fi
#   bench/python.sh topology [N]  instead: method="lewiner" on blocks of the real scans against the
#                              trilinear interpolant sampled 16x finer, up to N (15) differing blocks a scan
#                              (bench/python_trilinear_topology.py)
if [ "${1:-}" = topology ]; then
  [ -f data/ch2better.nii.gz ] || scripts/fetch_data.sh
  for case in "data/ch2.nii.gz 40.5" "data/ch2better.nii.gz 40.5" "256x256x108xi16:data/cranium.raw -423.5" \
              "256x256x108xi16:data/cranium.raw 200.5"; do
    PYTHONPATH=$build/python:bench /usr/bin/python3 bench/python_trilinear_topology.py $case 16 "${2:-15}"
  done
  exit 0
fi
if [ "${1:-}" = dask ]; then
  for mode in slabs memory cluster1 cluster2 slabs memory cluster1 cluster2; do
    $py bench/python_dask_mc.py "${2:-1024}" "${3:-64}" $mode
  done
  exit 0
fi
if [ "${1:-}" = lazy ]; then
  n=${2:-2048}
  $py bench/python_lazy.py "$n" "data/bench/lazy$n.vdiso"
  exit 0
fi
[ -f data/ch2better.nii.gz ] || scripts/fetch_data.sh
[ -f data/bench/head512.raw ] || $build/bin/vdiso synth data/bench/head512.raw --kind head --size 512 --quiet
cores=$(nproc)
echo "| volume | iso | method | threads | seconds | Mvoxels/s | triangles | peak above input (MB) | input (MB) |"
echo "|---|---|---|---|---|---|---|---|---|"
for case in "data/ch2better.nii.gz 40.5" "512x512x512xu16:data/bench/head512.raw 600.5"; do
  set -- $case
  for run in "vdiso 1 3" "vdiso $cores 3" "vtk 1 3" "vtk $cores 3" "skimage 1 1"; do
    set -- $case $run
    $py bench/python_mc.py "$1" "$2" "$3" "$4" "$5" | $py -c "
import json, sys
r = json.loads(sys.stdin.read())
name = r['volume'].split('/')[-1]
print(f\"| {name} | $2 | {r['method']} | {r['threads']} | {r['seconds']:.3f} | {r['mvoxels_per_s']:.0f} | {r['triangles']} | {r['peak_over_input_mb']:.0f} | {r['input_mb']:.0f} |\")"
  done
done
