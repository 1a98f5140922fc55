#!/usr/bin/env bash
# The paper's tables (Livnat & Hansen, "View Dependent Isosurface Extraction") regenerated on our
# data in one run, the paper's own figures beside ours:
#   Tables 1-2  octree, NOISE, WISE and SAGE at the distant, normal and closeup views: extraction
#               time, triangles (+ points), drawing time, bricks read, and the picture's
#               agreement with the octree's (vdiso compare);
#   Tables 3-4  SAGE with one feature at a time switched to WISE's choice (scan triangles not
#               polygons, exact boxes not the estimate, no points, top-down pyramid updates);
#   and SAGE against the visible-surface oracle (extract --oracle).
# The paper's rows are the Visible Woman's head (Tables 1 and 3), as ratios to its own octree
# (its machines are 20 years older: times are compared as SAGE / octree, not seconds).
# Data: the MRI (ch2better, mricron-data), the Debian CT (invesalius-examples' Cranium, skin and
# bone), the generated 512^3 head (skin and bone), and any store named: STORE.vdiso:ISO.
#
#   bench/paper.sh [SIZE] [STORE.vdiso:ISO ...]    image size, default 800; RUNS=N extractions
#                                                  per row (default 3): extract s is their median
set -euo pipefail
cd "$(dirname "$0")/.."
size=${1:-800}
shift || true
runs=${RUNS:-3}
vdiso=build/bin/vdiso
[ -x $vdiso ] || scripts/build.sh
scripts/fetch_data.sh
mkdir -p data/views data/bench
[ -f data/bench/head512.vdiso ] || $vdiso synth data/bench/head512.vdiso --kind head --size 512 --quiet
[ -f data/bench/ch2better.vdiso ] || $vdiso convert data/ch2better.nii.gz data/bench/ch2better.vdiso --quiet
[ -f data/bench/cranium.vdiso ] || $vdiso convert data/cranium.nhdr data/bench/cranium.vdiso --quiet
specs=("data/bench/ch2better.vdiso 40.5 skin" "data/bench/cranium.vdiso -423.5 skin" "data/bench/cranium.vdiso 200.5 bone"
       "data/bench/head512.vdiso 600.5 skin" "data/bench/head512.vdiso 1224.5 bone")
for extra in "$@"; do specs+=("${extra%:*} ${extra##*:} skin"); done

# The paper's Table 1 (Visible Woman head, SGI Onyx2): seconds and polygons, by surface, view,
# method; and Table 3 (Pentium 4): SAGE's extraction in ms by variant.
paper() {  # surface view method -> "ratio-to-octree-time polygons"
  python3 - "$@" <<'PY'
import sys
t1 = {("skin", "any", "octree"): (10.9, 1430824), ("skin", "any", "noise"): (10.2, 0),
      ("skin", "distant", "wise"): (35.1, 292242), ("skin", "distant", "sage"): (3.4, 18645),
      ("skin", "normal", "wise"): (35.8, 344628), ("skin", "normal", "sage"): (4.4, 195408),
      ("skin", "closeup", "wise"): (4.6, 43222), ("skin", "closeup", "sage"): (0.6, 36939),
      ("bone", "any", "octree"): (17.0, 2207592), ("bone", "any", "noise"): (14.6, 0),
      ("bone", "distant", "wise"): (13.9, 271075), ("bone", "distant", "sage"): (4.1, 12747),
      ("bone", "normal", "wise"): (32.7, 278735), ("bone", "normal", "sage"): (4.5, 153617),
      ("bone", "closeup", "wise"): (10.6, 84599), ("bone", "closeup", "sage"): (1.5, 67808)}
surface, view, method = sys.argv[1:4]
key = (surface, "any" if method in ("octree", "noise") else view, method)
octree = t1[(surface, "any", "octree")][0]
if key not in t1: print("-"); sys.exit()
s, polygons = t1[key]
print(f"{s / octree:.2f}" + (f", {polygons:,}" if polygons else ""))
PY
}
# The paper's Table 3 (head): SAGE's extraction ms for the variant against its full SAGE.
paper_ablation() {  # surface view variant
  python3 - "$@" <<'PY'
import sys
t3 = {"skin": {"distant": {"sage": 112, "triangles-scan": None, "exact-box": 159, "no-points": 1100},
               "normal": {"sage": 1205, "triangles-scan": 1857, "exact-box": 1294},
               "closeup": {"sage": 99, "triangles-scan": 155, "exact-box": 102}},
      "bone": {"distant": {"sage": 115, "exact-box": 169, "no-points": 1279},
               "normal": {"sage": 1380, "triangles-scan": 2062, "exact-box": 1512},
               "closeup": {"sage": 437, "triangles-scan": 615, "exact-box": 432}}}
surface, view, variant = sys.argv[1:4]
row = t3[surface][view]
print(f"{row[variant] / row['sage']:.2f}" if row.get(variant) else "-")
PY
}

octree_s="" row_s="" table=methods
row() {  # store iso surface view method label extra-args...; prints the row, sets row_s (its median)
  local store=$1 iso=$2 surface=$3 view=$4 method=$5 label=$6; shift 6
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
  row_s=$(python3 -c 'import statistics,sys; print(statistics.median(float(t) for t in sys.argv[1:]))' \
          "$(python3 -c 'import json,sys; print(json.load(sys.stdin)["extract_s"])' <<< "$stats")" $times)
  local theirs
  if [ "$table" = methods ]; then theirs=$(paper "$surface" "$view" "$method"); else theirs=$(paper_ablation "$surface" "$view" "$label"); fi
  python3 -c '
import json, statistics, sys
d = json.loads(sys.argv[1])
times = [d["extract_s"]] + [float(t) for t in sys.argv[7].split()]
s = statistics.median(times)
base = float(sys.argv[8]) if sys.argv[8] else s
print("| %s | %s | %s | %s | %.3f | %.2f | %s | %d + %d | %.3f | %d | %.1f | %s |" % (
    sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5], s, s / base, sys.argv[9], d["triangles"],
    d["points"], d.get("draw_s", 0), d["bricks_loaded"], d["bytes_read"] / 1e6, sys.argv[6]))' \
    "$stats" "$(basename "$store")" "$iso" "$view" "$label" "$agreement" "$times" "$octree_s" "$theirs"
}
echo "Tables 1-2. Extract s: median of $runs runs (page cache warm, default threads); the rest from"
echo "the first. \"/ octree\": this row's time over the octree's; paper: the same ratio in its Table 1"
echo "(Visible Woman head), and its polygons."
echo
table=methods
echo "| volume | iso | view | method | extract s | / octree | paper: / octree, polygons | triangles + points | draw s | bricks read | MB read | agreement with octree |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for spec in "${specs[@]}"; do
  set -- $spec
  for view in distant normal closeup; do
    octree_s=""
    row "$1" "$2" "$3" $view octree octree
    octree_s=$row_s
    for method in noise wise sage; do row "$1" "$2" "$3" $view $method $method; done
  done
done

echo
echo "Tables 3-4. SAGE with one feature at a time switched to WISE's choice; \"/ octree\" here is over"
echo "full SAGE's time, and paper: the same ratio in its Table 3 (\"-\": not in the paper)."
echo
table=ablation
echo "| volume | iso | view | variant | extract s | / sage | paper: / sage | triangles + points | draw s | bricks read | MB read | agreement with octree |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for spec in "${specs[@]}"; do
  set -- $spec
  for view in distant normal closeup; do
    octree_s=""
    row "$1" "$2" "$3" $view octree octree > /dev/null  # the reference picture
    row "$1" "$2" "$3" $view sage sage
    octree_s=$row_s
    row "$1" "$2" "$3" $view sage "triangles-scan" --scan triangles
    row "$1" "$2" "$3" $view sage "exact-box" --box exact
    row "$1" "$2" "$3" $view sage "no-points" --points off
    row "$1" "$2" "$3" $view sage "top-down" --update top-down
  done
done

echo
echo "SAGE against the visible-surface oracle (extract --oracle: the full surface's depth buffer"
echo "mapped back to cells and bricks, the least any view-dependent method needs)."
echo
echo "| volume | iso | view | triangles | points | oracle triangles | triangles / oracle | bricks read | oracle bricks | bricks / oracle | primitives per covered pixel | full / sage primitives |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for spec in "${specs[@]}"; do
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
