#!/usr/bin/env bash
# Speed on real scans beside the generated head, in one run, 1 thread against VTK's Flying Edges
# on 1 thread (from Python over the same samples: bench/fe_python.py):
#   one-shot   a fresh `vdiso extract` process per run, the store in the page cache (median)
#   per frame  the median warm frame of a 36-step orbit (--path orbit:36, frames 1..35)
# SAGE at the distant, normal and closeup views and vdiso's own octree (full surface), 1024^2;
# then the full extraction (octree) on 2 threads against 1 (median extract_s of REPEAT runs).
# Data: the Debian CT (data/cranium.nhdr: invesalius-examples' Cranium.inv3; skin -423.5, bone
# 200.5), the MRI (data/ch2better.nii.gz 40.5, data/ch2.nii.gz 40.5 with skin: mricron-data)
# and the generated head (vdiso synth --kind head --size 512: skin 600.5, bone 1224.5).
#
#   bench/real_scans.sh [REPEAT]       default 5
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh bench
repeat=${1:-5}
build=${BUILD_DIR:-build}
vdiso=$build/bin/vdiso
py=/usr/bin/python3
vdiso=$vdiso bench/real_stores.sh
rows=$(mktemp)
trap 'rm -f "$rows"' EXIT
# extract_s of `vdiso extract` with the given options, one JSON line per run.
oneshot() {
  local store=$1 iso=$2; shift 2
  for _ in $(seq "$repeat"); do
    $vdiso extract "data/bench/$store.vdiso" --iso "$iso" --threads 1 --size 1024x1024 --stats - --quiet "$@"
  done
}
for spec in "cranium -423.5 data/cranium.nhdr" "cranium 200.5 data/cranium.nhdr" \
            "ch2better 40.5 data/ch2better.nii.gz" "ch2 40.5 data/ch2.nii.gz" \
            "head512 600.5 512x512x512xu16:data/bench/head512.raw" "head512 1224.5 512x512x512xu16:data/bench/head512.raw"; do
  set -- $spec
  store=$1 iso=$2 src=$3
  fe=$($py bench/fe_python.py "$src" "$iso" 1 "$repeat")
  octree=$(oneshot "$store" "$iso" --method octree | $py -c "import json,sys,statistics; print(statistics.median(json.loads(l)['extract_s'] for l in sys.stdin))")
  for view in distant normal closeup; do
    sage=$(oneshot "$store" "$iso" --method sage --view $view)
    frames=$($vdiso extract "data/bench/$store.vdiso" --iso "$iso" --threads 1 --size 1024x1024 --method sage \
             --view $view --path orbit:36 --stats - --quiet)
    $py - "$store" "$iso" "$view" "$fe" "$octree" <<PY >> "$rows"
import json, statistics, sys
store, iso, view, fe, octree = sys.argv[1], sys.argv[2], sys.argv[3], json.loads(sys.argv[4]), float(sys.argv[5])
runs = [json.loads(l) for l in """$sage""".splitlines()]
frames = [json.loads(l) for l in """$frames""".splitlines()][1:]
one = statistics.median(r["extract_s"] for r in runs)
frame = statistics.median(f["extract_s"] for f in frames)
print(json.dumps({"store": store, "iso": iso, "view": view, "fe_s": fe["seconds"], "fe_triangles": fe["triangles"],
                  "octree_s": octree, "sage_s": one, "frame_s": frame, "triangles": runs[0]["triangles"],
                  "points": runs[0]["points"], "decode_s": statistics.median(r["decode_s"] for r in runs),
                  "io_s": statistics.median(r["io_s"] for r in runs),
                  "bytes_decoded": runs[0]["bricks_loaded"],
                  "visibility_ns": statistics.median(f["visibility_ns_per_triangle"] for f in frames),
                  "kernel_ns": statistics.median(f["kernel_ns_per_triangle"] for f in frames),
                  "coverage_ns": statistics.median(f["coverage_s"] / max(f["triangles"], 1) * 1e9 for f in frames)}))
PY
  done
done
$py - "$rows" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
# "bound": what SAGE would take if its triangles cost what the octree's do (the octree's time per
# triangle times SAGE's triangles: nothing spent on culling, projection or scan conversion);
# FE / bound is the most any view-dependent extraction of that surface could show against FE.
# Per kept triangle, medians over the warm frames (--stats, sampled: core/clock.h): SAGE's
# visibility work (cell tests, projection, coverage, box tests) and its kernel, beside FE's
# whole cost per triangle on this machine (Masked Occlusion Culling's published figure for
# comparison: about 12 ns a triangle rasterised, Hasselgren et al. 2016).
print("| scan | iso | view | FE s | octree s | SAGE one-shot s | FE / SAGE one-shot | SAGE / octree | SAGE frame s | FE / frame | triangles + points (FE) | FE / bound | visibility ns / kept tri | of which coverage | kernel ns / kept tri | FE ns / tri |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for r in rows:
    bound = r["octree_s"] / r["fe_triangles"] * r["triangles"]
    print(f"| {r['store']} | {r['iso']} | {r['view']} | {r['fe_s']:.3f} | {r['octree_s']:.3f} | {r['sage_s']:.3f} | "
          f"{r['fe_s'] / r['sage_s']:.1f}x | {r['sage_s'] / r['octree_s']:.2f} | {r['frame_s']:.4f} | "
          f"{r['fe_s'] / r['frame_s']:.1f}x | {r['triangles']} + {r['points']} ({r['fe_triangles']}) | {r['fe_s'] / bound:.1f}x | "
          f"{r['visibility_ns']:.0f} | {r['coverage_ns']:.0f} | {r['kernel_ns']:.0f} | {r['fe_s'] / r['fe_triangles'] * 1e9:.0f} |")
PY
echo
# 1 and 2 threads in turn, pair by pair, so that the machine's moods fall on both: the ratio
# is the median of the pairs' ratios (medians of separate runs swung 1.08x-1.84x on one scan).
echo "| scan | iso | octree 1 thread s | octree 2 threads s | 2 threads / 1 (median of pairs) |"
echo "|---|---|---|---|---|"
for spec in "cranium -423.5" "cranium 200.5" "ch2better 40.5" "ch2 40.5" "head512 600.5" "head512 1224.5"; do
  set -- $spec
  for _ in $(seq "$repeat"); do
    for threads in 1 2; do
      $vdiso extract "data/bench/$1.vdiso" --iso "$2" --threads $threads --method octree --stats - --quiet
    done
  done | $py -c "
import json, statistics, sys
s = [json.loads(l)['extract_s'] for l in sys.stdin]
one, two = s[0::2], s[1::2]
print(f'| {sys.argv[1]} | {sys.argv[2]} | {statistics.median(one):.4f} | {statistics.median(two):.4f} | '
      f'{statistics.median(a / b for a, b in zip(one, two)):.2f}x |')" "$1" "$2"
done
