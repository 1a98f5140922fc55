#!/usr/bin/env bash
# Beyond one machine (issue 14): vdiso-mpi with 1, 2 and 4 ranks on this 2-core machine, against
# vdiso itself, on the 1024^3 head.
#
#   bench/mpi.sh [REPEAT]        (REPEAT runs per row, median reported; default 3)
#
# Makes data/head1024.raw and data/head1024L.vdiso with `vdiso synth` when missing (2.1 and
# 1.8 GB). Every extraction reads its bricks cold from disk (--cold: O_DIRECT, the store's pages
# dropped); conversions drop the page cache first (bench/cold_run.sh; as root). Prints:
#   1. convert: wall seconds, per-rank input bytes read and store bytes written, halo bytes;
#   2. full extraction (octree) to a PLY: the job's seconds, per-rank bricks and bytes read,
#      mesh bytes written and bytes sent welding;
#   3. sage, normal view at 1024x1024, by image and by object: the job's seconds, bricks read in
#      all and by the busiest rank, coverage bytes and bytes gathered on rank 0.
# "job s" is rank 0's time from opening the store to the output written; "wall s" adds mpirun's
# start (about 0.3 s here) and MPI_Init.
set -euo pipefail
cd "$(dirname "$0")/.."
REPEAT=${1:-3}
V=build/bin/vdiso
M=build/bin/vdiso-mpi
DATA=data
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
[ -x "$M" ] || { echo "bench/mpi.sh: $M is not built (scripts/setup.sh installs OpenMPI)" >&2; exit 1; }
source bench/cold_run.sh

RAW="$DATA/head1024.raw"
S="$DATA/head1024L.vdiso"
[ -f "$RAW" ] || "$V" synth "$RAW" --kind head --size 1024 --quiet
[ -f "$S" ] || "$V" synth "$S" --kind head --size 1024 --quiet
ranksRun() { local n=$1; shift; mpirun --oversubscribe -np "$n" "$M" "$@"; }
median() { python3 -c "import sys,statistics; print(statistics.median(float(x) for x in sys.argv[1:]))" "$@"; }

# row LABEL JSON... : the median row of REPEAT stats files (one JSON each), by the job's seconds.
row() {
    local label=$1; shift
    python3 - "$label" "$@" <<'PY'
import json, statistics, sys
label, files = sys.argv[1], sys.argv[2:]
runs = [json.loads(open(f).read().splitlines()[0]) for f in files]
runs.sort(key=lambda d: d.get("extract_s", d.get("seconds", 0)))
d = runs[len(runs) // 2]
per = d.get("per_rank", [d])
def mb(x): return f"{x / 1e6:.1f}"
if d.get("method") == "octree":
    print(f"| {label} | {d['extract_s']:.2f} | {d['triangles']} | {d['bricks_loaded']} | "
          f"{' / '.join(mb(p['bytes_read']) for p in per)} | "
          f"{' / '.join(mb(p.get('mesh_bytes', 0)) for p in per)} | "
          f"{' / '.join(mb(p.get('weld_bytes_sent', 0)) for p in per)} |")
else:
    busiest = max(p["bricks_loaded"] for p in per)
    print(f"| {label} | {d['extract_s']:.3f} | {d['triangles']} | {d['bricks_loaded']} | {busiest} | "
          f"{mb(d['bytes_read'])} | {mb(d.get('coverage_bytes_per_rank', 0))} | {mb(d.get('gathered_bytes', 0))} |")
PY
}

echo "## 2. Full extraction (octree) of the skin to a PLY, cold, median of $REPEAT"
echo
echo "| run | job s | triangles | bricks read | MB read per rank | mesh MB written per rank | MB sent welding per rank |"
echo "|---|---|---|---|---|---|---|"
for t in 1 2; do
    files=()
    for k in $(seq "$REPEAT"); do
        "$V" extract "$S" --iso 600.5 --cold --threads $t --quiet -o "$TMP/one.ply" --force --stats "$TMP/o$t.$k.json"
        files+=("$TMP/o$t.$k.json")
    done
    row "vdiso, $t thread$([ $t = 1 ] || echo s)" "${files[@]}"
done
for n in 1 2 4; do
    files=()
    for k in $(seq "$REPEAT"); do
        ranksRun $n extract "$S" --iso 600.5 --cold --quiet -o "$TMP/m.ply" --force --stats "$TMP/m$n.$k.json"
        files+=("$TMP/m$n.$k.json")
    done
    row "vdiso-mpi, $n rank$([ $n = 1 ] || echo s)" "${files[@]}"
done
cmp -s "$TMP/one.ply" "$TMP/m.ply" && echo && echo "(the 4-rank PLY is the single process's, byte for byte)"
echo

echo "## 3. SAGE, normal view at 1024x1024, cold, full resolution (--lod-error 0), median of $REPEAT"
echo
echo "| run | job s | triangles | bricks read | busiest rank's | MB read | coverage MB per rank | MB gathered |"
echo "|---|---|---|---|---|---|---|---|"
SAGE=(--iso 600.5 --method sage --size 1024x1024 --lod-error 0 --cold --quiet --force)
for t in 1 2; do
    files=()
    for k in $(seq "$REPEAT"); do
        "$V" extract "$S" "${SAGE[@]}" --threads $t --stats "$TMP/s$t.$k.json" --png "$TMP/one$t.png"
        files+=("$TMP/s$t.$k.json")
    done
    row "vdiso, $t thread$([ $t = 1 ] || echo s)" "${files[@]}"
done
for p in image object; do
    for n in 1 2 4; do
        files=()
        for k in $(seq "$REPEAT"); do
            ranksRun $n extract "$S" "${SAGE[@]}" --partition $p --stats "$TMP/$p$n.$k.json" --png "$TMP/$p$n.png"
            files+=("$TMP/$p$n.$k.json")
        done
        row "vdiso-mpi by $p, $n rank$([ $n = 1 ] || echo s)" "${files[@]}"
    done
done
echo
for p in image object; do
    echo "picture of 4 ranks by $p against vdiso's: $("$V" compare "$TMP/one1.png" "$TMP/${p}4.png")"
done
