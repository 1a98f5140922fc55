#!/usr/bin/env bash
# Post-processing out of core (vdiso extract --smooth, --decimate, --largest, --min-piece) on a
# generated head's skin: time and peak memory of each, median of N runs, against the plain
# extraction in the same run.
#
#   bench/post.sh [SIZE] [RUNS] [THREADS]     default: 2048 3 2
#
# Generates data/headSIZEL.vdiso (synth, with levels) if missing: 15 GB for 2048. Writes the
# meshes to data/post_bench.ply (removed at the end). The store's pages are warm after the first
# run; post-processing reads only its own spool, which is what is timed as post_s.
set -euo pipefail
cd "$(dirname "$0")/.."
size=${1:-2048}
runs=${2:-3}
threads=${3:-2}
vdiso=build/bin/vdiso
[ -x $vdiso ] || scripts/build.sh
mkdir -p data
store=data/head${size}L.vdiso
[ -f $store ] || $vdiso synth $store --kind head --size $size --quiet
out=data/post_bench.ply
trap 'rm -f $out /tmp/vdiso_post_bench.*' EXIT

echo "| operation | triangles in | triangles out | runs | extract s | post s | pieces s | wall s | peak RSS MB | spool MB |"
echo "|---|---|---|---|---|---|---|---|---|---|"
row() {  # label options...
  local label=$1; shift
  : > /tmp/vdiso_post_bench.rows
  for _ in $(seq "$runs"); do
    /usr/bin/time -f "%e %M" -o /tmp/vdiso_post_bench.time \
      $vdiso extract $store --iso 600.5 --cache-mb 512 --threads $threads -o $out --force --quiet \
      --stats /tmp/vdiso_post_bench.json "$@"
    python3 - "$(cat /tmp/vdiso_post_bench.time)" >> /tmp/vdiso_post_bench.rows <<'PY'
import json, sys
wall, kb = sys.argv[1].split()
s = json.load(open("/tmp/vdiso_post_bench.json"))
print(s.get("triangles_extracted", s["triangles"]), s["triangles"], s["extract_s"], s.get("post_s", 0),
      s.get("pieces_s", 0), wall, int(kb) / 1024, s.get("post_spool_mb", 0))
PY
  done
  python3 - "$label" "$runs" /tmp/vdiso_post_bench.rows <<'PY'
import statistics, sys
rows = [list(map(float, l.split())) for l in open(sys.argv[3]) if l.strip()]
med = lambda i: statistics.median(r[i] for r in rows)
print(f"| {sys.argv[1]} | {int(rows[0][0]):,} | {int(rows[0][1]):,} | {sys.argv[2]} | {med(2):.2f} | "
      f"{med(3):.2f} | {med(4):.2f} | {med(5):.2f} | {max(r[6] for r in rows):.0f} | {rows[0][7]:.0f} |")
PY
}

row "extract only (streamed)"
row "--smooth 10" --smooth 10
row "--smooth 30 (halo of 2 slabs)" --smooth 30
row "--decimate 0.1" --decimate 0.1
row "--largest" --largest
row "--min-piece 100000" --min-piece 100000
row "--largest --smooth 10 --decimate 0.1" --largest --smooth 10 --decimate 0.1
