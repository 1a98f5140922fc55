#!/usr/bin/env bash
# Levels of detail (issue 13): what they buy, cold from disk, against full resolution and the
# full-resolution octree's picture.
#
#   bench/lod.sh [REPEAT]        (REPEAT cold runs per timed row, median reported; default 3)
#
# Makes data/head{1024,2048,2560}L.vdiso with `vdiso synth` when missing (1.8, 15 and 28 GB;
# levels until one brick, the default), then prints:
#   1. cold distant views at 1024x1024: bytes read as a share of the store, with and without levels;
#   2. the 2560^3 head's cold normal view at 1024x1024 on 1 and 2 threads, with and without
#      levels, and the agreement of the normal and closeup views at --lod-error 1 with the
#      full-resolution octree's picture;
#   3. the curve: bytes read and extraction time against camera distance (the normal view's
#      distance times 1 .. 24), with and without levels, with and without occlusion culling,
#      on the 2560^3 head, cold, 2 threads, times the median of REPEAT; bench/lod/curve.csv and
#      bench/lod/curve.png (gnuplot).
# Every row is one `vdiso extract --cold`: the store's pages are dropped, bricks come from disk.
set -euo pipefail
cd "$(dirname "$0")/.."
REPEAT=${1:-3}
V=build/bin/vdiso
DATA=data
OUT=bench/lod
mkdir -p "$OUT" "$DATA"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
command -v gnuplot >/dev/null || { echo "bench/lod.sh: needs gnuplot (apt-get install gnuplot-nox)" >&2; exit 1; }

for n in 1024 2048 2560; do
    [ -f "$DATA/head${n}L.vdiso" ] || "$V" synth "$DATA/head${n}L.vdiso" --kind head --size "$n" --quiet
done

# extract STORE ARGS... -> prints the stats JSON
extract() { "$V" extract "$@" --iso 600.5 --method sage --cold --quiet --stats - --force; }
field() { python3 -c "import json,sys; d=json.load(sys.stdin); print(d['$1'])"; }
median() { python3 -c "import sys,statistics; print(statistics.median(float(x) for x in sys.argv[1:]))" "$@"; }
storeBytes() { stat -c %s "$1"; }

echo "## 1. Cold distant views, 1024x1024, 1 thread"
echo
echo "| volume | store MB | levels | bricks read | MB read | share of the store | extract s | tree s |"
echo "|---|---|---|---|---|---|---|---|"
for n in 1024 2048 2560; do
    s="$DATA/head${n}L.vdiso"
    for lod in 0 1; do
        j=$(extract "$s" --view distant --size 1024x1024 --threads 1 --lod-error $lod)
        python3 - "$j" "$(storeBytes "$s")" "$n" "$lod" <<'EOF'
import json, sys
d = json.loads(sys.argv[1]); size = int(sys.argv[2])
print(f"| {sys.argv[3]}^3 | {size/1e6:.0f} | {'on' if sys.argv[4] == '1' else 'off'} | {d['bricks_loaded']} | "
      f"{d['bytes_read']/1e6:.2f} | {100*d['bytes_read']/size:.4f}% | {d['extract_s']:.3f} | {d['tree_s']:.3f} |")
EOF
    done
done
echo

S="$DATA/head2560L.vdiso"
echo "## 2. The 2560^3 head, cold normal view, 1024x1024 (median of $REPEAT)"
echo
echo "extract s: the frame; + tree: with building the min/max tree over all levels' bricks, which"
echo "a single \`vdiso extract\` does first and the frames of a path or a server share."
echo
echo "| threads | levels | extract s | + tree s | bricks read | MB read | triangles | points |"
echo "|---|---|---|---|---|---|---|---|"
for threads in 1 2; do
    for lod in 0 1; do
        times=()
        total=()
        for r in $(seq "$REPEAT"); do
            j=$(extract "$S" --view normal --size 1024x1024 --threads $threads --lod-error $lod)
            times+=("$(echo "$j" | field extract_s)")
            total+=("$(echo "$j" | python3 -c "import json,sys; d=json.load(sys.stdin); print(d['extract_s'] + d['tree_s'])")")
        done
        python3 - "$j" "$(median "${times[@]}")" "$threads" "$lod" "$(median "${total[@]}")" <<'EOF'
import json, sys
d = json.loads(sys.argv[1])
print(f"| {sys.argv[3]} | {'on' if sys.argv[4] == '1' else 'off'} | {float(sys.argv[2]):.3f} | {float(sys.argv[5]):.3f} | "
      f"{d['bricks_loaded']} | {d['bytes_read']/1e6:.1f} | {d['triangles']} | {d['points']} |")
EOF
    done
done
echo
echo "Agreement with the full-resolution octree's picture (vdiso compare, covered pixels):"
echo
for view in normal closeup distant; do
    "$V" extract "$S" --iso 600.5 --method octree --view $view --size 1024x1024 --png "$TMP/octree_$view.png" --quiet --force
    "$V" extract "$S" --iso 600.5 --method sage --view $view --size 1024x1024 --lod-error 1 --png "$TMP/lod_$view.png" --quiet --force
    echo "- $view, --lod-error 1: $("$V" compare "$TMP/octree_$view.png" "$TMP/lod_$view.png" | tail -1)"
done
echo

echo "## 3. Bytes read and time (median of $REPEAT) against distance (2560^3 head, cold, 1024x1024, 2 threads)"
echo
CSV="$OUT/curve.csv"
echo "scale,distance,levels,occlusion,bytes_read,extract_s,bricks_read,triangles,points" > "$CSV"
for scale in 1 1.5 2 3 4 6 8 12 16 24; do
    python3 - "$scale" > "$TMP/cam.json" <<'EOF'
import json, math, sys
# The normal preset (core/camera.h): looks at the centre along normalize(0.35, 1, 0.3) from the
# distance at which the bounding sphere fills the view; here that distance times `scale`.
s = float(sys.argv[1]); lo, hi = 0.0, 2559.0
c = [(lo + hi) / 2] * 3; r = math.sqrt(3) * (hi - lo) / 2
d = [0.35, 1.0, 0.3]; n = math.sqrt(sum(x * x for x in d)); d = [x / n for x in d]
dist = r / math.sin(math.radians(15)) * s
print(json.dumps({"eye": [c[k] + d[k] * dist for k in range(3)], "target": c, "up": [0, 0, 1],
                  "fov": 30, "width": 1024, "height": 1024}))
EOF
    dist=$(python3 -c "import json; c=json.load(open('$TMP/cam.json')); print(round(sum((c['eye'][k]-c['target'][k])**2 for k in range(3))**0.5))")
    for lod in 0 1; do
        for occ in on off; do
            times=()
            for r in $(seq "$REPEAT"); do
                j=$(extract "$S" --camera "$TMP/cam.json" --lod-error $lod --occlusion $occ)
                times+=("$(echo "$j" | field extract_s)")
            done
            python3 - "$j" "$scale" "$dist" "$lod" "$occ" "$(median "${times[@]}")" >> "$CSV" <<'EOF'
import json, sys
d = json.loads(sys.argv[1])
print(f"{sys.argv[2]},{sys.argv[3]},{'on' if sys.argv[4] == '1' else 'off'},{sys.argv[5]},{d['bytes_read']},"
      f"{float(sys.argv[6]):.4f},{d['bricks_loaded']},{d['triangles']},{d['points']}")
EOF
        done
    done
done
python3 - "$CSV" <<'EOF'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
print("| distance (x normal) | levels+occlusion MB / s | levels only MB / s | occlusion only MB / s | neither MB / s |")
print("|---|---|---|---|---|")
for scale in dict.fromkeys(r["scale"] for r in rows):
    cells = []
    for lod, occ in (("on", "on"), ("on", "off"), ("off", "on"), ("off", "off")):
        r = next(r for r in rows if r["scale"] == scale and r["levels"] == lod and r["occlusion"] == occ)
        cells.append(f"{int(r['bytes_read'])/1e6:.1f} / {float(r['extract_s']):.2f}")
    print(f"| {scale} | " + " | ".join(cells) + " |")
EOF
python3 - "$CSV" "$TMP" <<'EOF'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
for lod in ("on", "off"):
    for occ in ("on", "off"):
        with open(f"{sys.argv[2]}/{lod}_{occ}.dat", "w") as f:
            for r in rows:
                if r["levels"] == lod and r["occlusion"] == occ:
                    f.write(f"{r['scale']} {int(r['bytes_read'])/1e6} {r['extract_s']}\n")
EOF
gnuplot <<EOF
set terminal pngcairo size 1200,500 font ",10"
set output "$OUT/curve.png"
set multiplot layout 1,2 title "2560^3 generated head, skin, cold reads, 1024x1024, 2 threads (bench/lod.sh)"
set logscale xy
set xrange [0.9:30]
set xlabel "camera distance (x the normal view's)"
set key top right
set grid
set ylabel "MB read"
plot "$TMP/on_on.dat" using 1:2 with linespoints title "levels + occlusion culling", \
     "$TMP/on_off.dat" using 1:2 with linespoints title "levels only", \
     "$TMP/off_on.dat" using 1:2 with linespoints title "occlusion culling only", \
     "$TMP/off_off.dat" using 1:2 with linespoints title "neither (frustum and range only)"
set ylabel "extraction time, s"
plot "$TMP/on_on.dat" using 1:3 with linespoints title "levels + occlusion culling", \
     "$TMP/on_off.dat" using 1:3 with linespoints title "levels only", \
     "$TMP/off_on.dat" using 1:3 with linespoints title "occlusion culling only", \
     "$TMP/off_off.dat" using 1:3 with linespoints title "neither (frustum and range only)"
unset multiplot
EOF
echo
echo "Curve: $CSV, $OUT/curve.png"
