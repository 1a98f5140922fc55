#!/usr/bin/env bash
# The paper's Table 1 in our terms, plus the ablation of Tables 3-4, measured in one run:
# octree, noise, wise and sage on distant, normal and closeup views, skin and bone of the
# 512^3 generated head and the skin of the real MRI (ch2, which has skin). Each row renders
# its surface (draw_s) and compares the picture with octree's (vdiso compare).
#
#   bench/views.sh [SIZE]     image size, default 800; RUNS=N extractions per row (default 3):
#                             extract s is their median, the rest comes from the first
set -euo pipefail
cd "$(dirname "$0")/.."
size=${1:-800}
runs=${RUNS:-3}
vdiso=build/bin/vdiso
[ -x $vdiso ] || scripts/build.sh
mkdir -p data/views
[ -f data/head512.vdiso ] || $vdiso synth data/head512.vdiso --kind head --size 512 --quiet
if [ ! -f data/ch2.vdiso ]; then
  scripts/fetch_data.sh
  $vdiso convert data/ch2.nii.gz data/ch2.vdiso --quiet
fi

row() {  # store iso view method label extra-args...
  local store=$1 iso=$2 view=$3 method=$4 label=$5; shift 5
  local png=data/views/$(basename "$store" .vdiso)_${iso}_${view}_${label}.png
  local stats times=""
  stats=$($vdiso extract "$store" --iso "$iso" --method "$method" --view "$view" \
          --size ${size}x${size} --png "$png" --stats - --force --quiet "$@")
  local frame=()  # the full methods take no camera without a picture to frame
  case $method in sage|wise) frame=(--view "$view" --size ${size}x${size}) ;; esac
  for ((r = 1; r < runs; r++)); do
    times="$times $($vdiso extract "$store" --iso "$iso" --method "$method" "${frame[@]}" \
          --stats - --quiet "$@" |
          python3 -c 'import json,sys; print(json.load(sys.stdin)["extract_s"])')"
  done
  local agreement="1"
  if [ "$label" != octree ]; then
    agreement=$($vdiso compare "data/views/$(basename "$store" .vdiso)_${iso}_${view}_octree.png" "$png" |
                awk '{print $2}' | tr -d :)
  fi
  python3 -c '
import json, statistics, sys
d = json.loads(sys.argv[1])
times = [d["extract_s"]] + [float(t) for t in sys.argv[7].split()]
print("| %s | %s | %s | %s | %.3f | %d | %d | %.3f | %d | %.1f | %s |" % (
    sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5], statistics.median(times), d["triangles"],
    d["points"], d.get("draw_s", 0), d["bricks_loaded"], d["bytes_read"] / 1e6, sys.argv[6]))' \
    "$stats" "$(basename "$store")" "$iso" "$view" "$label" "$agreement" "$times"
}

echo "Extract s: median of $runs runs; the rest from the first. Page cache warm."
echo
echo "| volume | iso | view | method | extract s | triangles | points | draw s | bricks read | MB read | agreement with octree |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for spec in "data/head512.vdiso 600.5" "data/head512.vdiso 1224.5" "data/ch2.vdiso 40.5"; do
  set -- $spec
  for view in distant normal closeup; do
    row "$1" "$2" $view octree octree
    row "$1" "$2" $view noise noise
    row "$1" "$2" $view wise wise
    row "$1" "$2" $view sage sage
  done
done

echo
echo "Ablation (Tables 3-4): SAGE with one feature at a time switched to WISE's choice."
echo
echo "| volume | iso | view | variant | extract s | triangles | points | draw s | bricks read | MB read | agreement with octree |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for view in distant normal closeup; do
  row data/head512.vdiso 600.5 $view sage sage
  row data/head512.vdiso 600.5 $view sage "triangles-scan" --scan triangles
  row data/head512.vdiso 600.5 $view sage "exact-box" --box exact
  row data/head512.vdiso 600.5 $view sage "no-points" --points off
  row data/head512.vdiso 600.5 $view sage "top-down" --update top-down
done

echo
echo "SAGE against the visible-surface oracle (extract --oracle: the full surface's depth buffer"
echo "mapped back to cells and bricks, the least any view-dependent method needs)."
echo
echo "| volume | iso | view | triangles | points | oracle triangles | triangles / oracle | bricks read | oracle bricks | bricks / oracle | primitives per covered pixel | full / sage primitives |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for spec in "data/head512.vdiso 600.5" "data/head512.vdiso 1224.5" "data/ch2.vdiso 40.5"; do
  set -- $spec
  for view in distant normal closeup; do
    $vdiso extract "$1" --iso "$2" --method sage --view $view --size ${size}x${size} --oracle --stats - --quiet |
      python3 -c '
import json, sys
d = json.load(sys.stdin)
prims = d["triangles"] + d["points"]
print("| %s | %s | %s | %d | %d | %d | %.2f | %d | %d | %.2f | %.2f | %.0f |" % (
    sys.argv[1], sys.argv[2], sys.argv[3], d["triangles"], d["points"], d["oracle_triangles"],
    d["triangles_over_oracle"], d["bricks_loaded"], d["oracle_bricks"], d["bricks_over_oracle"],
    d["primitives_per_pixel"], d["full_triangles"] / max(1, prims)))' "$(basename "$1")" "$2" "$view"
  done
done
