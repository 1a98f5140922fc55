#!/usr/bin/env bash
# vdiso's full extraction (octree) against VTK 9.1's vtkFlyingEdges3D and vtkMarchingCubes on
# the same volumes and isovalues: time, throughput, triangles and surface area.
#
#   bench/compare_vtk.sh [REPEAT]      default: 3 runs per method (median)
#   JOBS=1 bench/compare_vtk.sh        build with one job when another build shares the machine
#
# Builds build-vtk/ with VDISO_BUILD_VTK_COMPARE=ON (needs libvtk9-dev), generates
# data/head512.vdiso and converts data/ch2better.nii.gz if missing, then prints a Markdown
# table. "vdiso octree" has every brick decoded already (extraction alone); "incl. decode" is
# the first run over a cold cache. Area ratio and triangle ratio are to "vdiso octree".
set -euo pipefail
cd "$(dirname "$0")/.."
repeat=${1:-3}
build=build-vtk
bench/build_vtk.sh vdiso vdiso_vtk_compare

mkdir -p data
[ -f data/head512.vdiso ] || $build/bin/vdiso synth data/head512.vdiso --kind head --size 512 --quiet
if [ ! -f data/ch2better.vdiso ]; then
  [ -f data/ch2better.nii.gz ] || scripts/fetch_data.sh
  $build/bin/vdiso convert data/ch2better.nii.gz data/ch2better.vdiso
fi

json=$(mktemp)
trap 'rm -f "$log" "$json"' EXIT
# compare VOLUME ISO THREADS [extra options]: appends the program's JSON lines to $json.
compare() {
  local volume=$1 iso=$2 threads=$3; shift 3
  $build/bin/vdiso_vtk_compare data/$volume.vdiso --iso "$iso" --vtk-threads "$threads" \
    --repeat "$repeat" --json "$@" | grep '^{' >> "$json"
}
compare head512 600.5 1
compare head512 600.5 2 --no-marching-cubes
compare head512 1224.5 1
compare head512 1224.5 2 --no-marching-cubes
compare ch2better 40.5 1
compare ch2better 40.5 2 --no-marching-cubes

echo "| volume | iso | method | threads | seconds | Mvoxels/s | triangles | area | area ratio | triangle ratio |"
echo "|---|---|---|---|---|---|---|---|---|---|"
# The runs with 2 VTK threads repeat the vdiso rows of the 1-thread runs: keep only their VTK rows.
python3 - "$json" <<'EOF'
import json, os, sys
seen = set()
for line in open(sys.argv[1]):
    r = json.loads(line)
    volume = os.path.basename(r["volume"]).removesuffix(".vdiso")
    key = (volume, r["iso"], r["method"], r["threads"])
    if r["method"].startswith("vdiso") and key in seen:
        continue
    seen.add(key)
    print(f'| {volume} | {r["iso"]:g} | {r["method"]} | {r["threads"]} | {r["seconds"]:.3f} | '
          f'{r["voxels_per_s"] / 1e6:.0f} | {r["triangles"]:,} | {r["area"]:.6g} | '
          f'{r["area_ratio_to_vdiso"]:.5f} | {r["triangle_ratio_to_vdiso"]:.3f} |')
EOF
