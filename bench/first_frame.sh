#!/usr/bin/env bash
# The time targets of the out-of-core and speed issues, measured as medians: a cold normal view
# (SAGE on 1 thread, and with vdiso's default options: every core, here 2 as the baseline's)
# against reading the raw volume whole from cold disk and running VTK Flying Edges on 2 threads, alternated RUNS times in one run so that the disk's
# and the machine's moods fall on all. Wall time of the whole vdiso process (start-up, index,
# extraction) against the baseline's read + Flying Edges.
#
#   bench/first_frame.sh [SIZE] [RUNS]     default 1024 5 (needs data/headSIZE.raw, .vdiso:
#                                          bench/io.sh SIZE makes them)
set -euo pipefail
cd "$(dirname "$0")/.."
size=${1:-1024}
runs=${2:-5}
raw=data/head$size.raw
store=data/head$size.vdiso
bench/build_vtk.sh vdiso vdiso_raw_baseline
vdiso=build-vtk/bin/vdiso
[ -f $raw ] && [ -f $store ] || { echo "needs $raw and $store (bench/io.sh $size)"; exit 1; }

echo "| iso | run | sage 1 thread wall s | sage default options wall s | sage default extract s | baseline read s | baseline Flying Edges s | baseline s |"
echo "|---|---|---|---|---|---|---|---|"
stats=$(mktemp)
trap 'rm -f "$stats"' EXIT
# Wall time of one cold SAGE run (the stats file is read after the clock stops).
sage() {
  local start=$(date +%s.%N)
  local threads=()
  [ "$2" = default ] || threads=(--threads $2)
  $vdiso extract $store --iso $1 --method sage --view normal --cold "${threads[@]}" --stats $stats --force --quiet
  python3 -c "print($(date +%s.%N) - $start)"
}
for iso in 600.5 1224.5; do
  for ((r = 1; r <= runs; r++)); do
    wall1=$(sage $iso 1)
    wall2=$(sage $iso default)
    extract=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["extract_s"])' $stats)
    base=$(build-vtk/bin/vdiso_raw_baseline $raw --dims $size,$size,$size --type u16 --iso $iso --threads 2 2>/dev/null)
    python3 -c '
import json, sys
b = json.loads(sys.argv[6])
print("| %s | %s | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f |" % (sys.argv[1], sys.argv[2], float(sys.argv[3]),
      float(sys.argv[4]), float(sys.argv[5]), b["read_s"], b["flying_edges_s"], b["total_s"]))' $iso $r $wall1 $wall2 $extract "$base"
  done
done | tee /tmp/vdiso_first_frame.md
echo
python3 - <<'PY'
import statistics
rows = [l.split("|")[1:-1] for l in open("/tmp/vdiso_first_frame.md") if l.startswith("| ") and l[2].isdigit()]
for iso in sorted({r[0].strip() for r in rows}):
    mine = [r for r in rows if r[0].strip() == iso]
    base = [float(r[7]) for r in mine]
    mb = statistics.median(base)
    for column, what in ((2, "sage 1 thread"), (3, "sage default options")):
        sage = [float(r[column]) for r in mine]
        ms = statistics.median(sage)
        print("iso %s: %s median %.3f s, baseline median %.3f s: %.1fx sooner (runs: %.1f-%.1fx)" % (
            iso, what, ms, mb, mb / ms, min(b / s for b, s in zip(base, sage)), max(b / s for b, s in zip(base, sage))))
PY
rm -f /tmp/vdiso_first_frame.md
