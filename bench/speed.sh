#!/usr/bin/env bash
# The speed issue's targets in one run: SAGE's distant, normal and closeup views at SIZE x SIZE
# and vdiso's full extraction (octree) against VTK's Flying Edges, the same number of threads on
# both sides (1 and 2), skin and bone of the generated 512^3 head and the skin of the MRI.
#
#   bench/speed.sh [REPEAT] [SIZE]     default 5 runs per row (median), 1024
#
# Every row runs in one process per volume, isovalue and thread count (vdiso_vtk_compare):
# "in memory" has every brick decoded already, as VTK has the volume; "from store" starts each
# run from an empty brick cache (page cache warm), as `vdiso extract` does. Ratios are Flying
# Edges' seconds over the row's, on the same threads.
set -euo pipefail
cd "$(dirname "$0")/.."
repeat=${1:-5}
size=${2:-1024}
bench/build_vtk.sh vdiso vdiso_vtk_compare
build=build-vtk
mkdir -p data
[ -f data/head512.vdiso ] || $build/bin/vdiso synth data/head512.vdiso --kind head --size 512 --quiet
if [ ! -f data/ch2better.vdiso ]; then
  [ -f data/ch2better.nii.gz ] || scripts/fetch_data.sh
  $build/bin/vdiso convert data/ch2better.nii.gz data/ch2better.vdiso --quiet
fi
json=$(mktemp)
trap 'rm -f "$json"' EXIT
for spec in "head512 600.5" "head512 1224.5" "ch2better 40.5"; do
  set -- $spec
  for threads in 1 2; do
    $build/bin/vdiso_vtk_compare data/$1.vdiso --iso $2 --threads $threads --vtk-threads $threads \
      --repeat "$repeat" --no-marching-cubes --views distant,normal,closeup --size "$size" --json |
      grep '^{' >> "$json"
  done
done
python3 - "$json" "$size" <<'PY'
import json, os, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
fe = {(r["volume"], r["iso"], r["threads"]): r["seconds"] for r in rows if r["method"] == "vtkFlyingEdges3D"}
print(f"| volume | iso | method | threads | seconds | Flying Edges s | FE / method | triangles + points |")
print("|---|---|---|---|---|---|---|---|")
for r in rows:
    if r["method"] in ("vtkFlyingEdges3D", "vdiso octree incl. decode"):
        continue
    base = fe[(r["volume"], r["iso"], r["threads"])]
    name = os.path.basename(r["volume"]).removesuffix(".vdiso")
    print(f'| {name} | {r["iso"]:g} | {r["method"]} | {r["threads"]} | {r["seconds"]:.4f} | {base:.4f} | '
          f'{base / r["seconds"]:.1f} | {r["triangles"]:,} |')
PY
