#!/usr/bin/env bash
# Beyond one machine (issue 14): vdiso-mpi with 1, 2 and 4 ranks on this 2-core machine, against
# vdiso itself, on the 1024^3 head.
#
#   bench/mpi.sh [REPEAT]        (REPEAT runs per row, median reported; default 3)
#
# Makes data/head1024.raw and data/head1024L.vdiso with `vdiso synth` when missing (2.1 and
# 1.8 GB). Every extraction reads its bricks cold from disk (--cold: O_DIRECT, the store's pages
# dropped); conversions drop the page cache first (bench/cold_run.sh; as root). Prints:
#   1. convert: wall seconds, per-rank input bytes read and store bytes written, halo bytes
#      (vdiso-mpi's ranks compress on one thread each, vdiso on both cores);
#   2. full extraction (octree) to a PLY: the job's seconds, per-rank bricks and bytes read,
#      mesh bytes written and bytes sent welding;
#   3. sage, normal view at 1024x1024, by image and by object: the job's seconds, bricks read in
#      all and by the busiest rank, coverage bytes and bytes gathered on rank 0.
# "job s" is rank 0's time from opening the store to the output written (vdiso's extract_s,
# with tree_s for sage); "wall s" is the whole command: for vdiso-mpi with mpirun's start and
# MPI_Init, for both the mesh file synced and closed, and the picture drawn.
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
median() { python3 -c "import sys,statistics; print(statistics.median(float(x) for x in sys.argv[1:]))" "$@"; }

# row LABEL JSON... : the median row of REPEAT stats files (one JSON each), by the job's seconds.
row() {
    local label=$1 wall=$2; shift 2
    python3 - "$label" "$wall" "$@" <<'PY'
import json, statistics, sys
label, wall, files = sys.argv[1], float(sys.argv[2]), sys.argv[3:]
runs = [json.loads(open(f).read().splitlines()[0]) for f in files]
runs.sort(key=lambda d: d.get("extract_s", d.get("seconds", 0)))
d = runs[len(runs) // 2]
per = d.get("per_rank", [d])
def mb(x): return f"{x / 1e6:.1f}"
def kb(x): return f"{x / 1e3:.1f}"
if d.get("method") == "octree":
    print(f"| {label} | {d['extract_s']:.2f} | {wall:.2f} | {d['triangles']} | {d['bricks_loaded']} | "
          f"{' / '.join(mb(p['bytes_read']) for p in per)} | "
          f"{' / '.join(mb(p.get('mesh_bytes', 0)) for p in per)} | "
          f"{' / '.join(kb(p.get('weld_bytes_sent', 0)) for p in per)} |")
else:
    busiest = max(p["bricks_loaded"] for p in per)
    # vdiso builds the min/max tree before the frame (tree_s); vdiso-mpi's job time includes it.
    print(f"| {label} | {d['extract_s'] + d.get('tree_s', 0):.3f} | {wall:.2f} | {d['triangles']} | {d['bricks_loaded']} | {busiest} | "
          f"{mb(d['bytes_read'])} | {mb(d.get('coverage_bytes_per_rank', 0))} | {mb(d.get('gathered_bytes', 0))} |")
PY
}

if [ "${SKIP_CONVERT:-0}" = 0 ]; then
echo "## 1. Convert the raw 1024^3 u16 head (2,147 MB), input cold, median of $REPEAT"
echo
echo "| run | wall s | MB/s in | MB read per rank | MB written per rank | halo MB sent per rank | peak MB (largest rank) |"
echo "|---|---|---|---|---|---|---|"
OUTS="$DATA/mpi_bench_out.vdiso"
CONVERT=("$RAW" --dims 1024,1024,1024 --type u16 "$OUTS" --force --quiet)
convertRow() {  # LABEL JSON WALLS...: the median wall time; per-rank figures and peak from the last run
    local label=$1 json=$2; shift 2
    local s; s=$(median "$@")
    python3 - "$label" "$s" "$json" "$(stat -c %s "$RAW")" "$peak" <<'PY'
import json, sys
label, s, path, size, peak = sys.argv[1], float(sys.argv[2]), sys.argv[3], int(sys.argv[4]), sys.argv[5]
per = json.loads(open(path).read())["per_rank"] if path != "-" else []
def mb(x): return f"{x / 1e6:.0f}"
cols = [" / ".join(mb(p[k]) for p in per) if per else "-" for k in ("bytes_read", "bytes_written", "halo_bytes_sent")]
print(f"| {label} | {s:.2f} | {size / 1e6 / s:.0f} | {cols[0]} | {cols[1]} | {cols[2]} | {int(peak) // 1024} |")
PY
}
walls=()
for k in $(seq "$REPEAT"); do
    drop; read -r w peak < <(measure "$V" convert "${CONVERT[@]}"); walls+=("$w")
done
convertRow "vdiso (TBB on both cores)" - "${walls[@]}"
for n in 1 2 4; do
    walls=()
    for k in $(seq "$REPEAT"); do
        drop; read -r w peak < <(measure mpirun --oversubscribe -np $n "$M" convert "${CONVERT[@]}" --stats "$TMP/c.json")
        walls+=("$w")
    done
    convertRow "vdiso-mpi, $n rank$([ $n = 1 ] || echo s)" "$TMP/c.json" "${walls[@]}"
done
rm -f "$OUTS"
echo
fi

echo "## 2. Full extraction (octree) of the skin to a PLY, cold, median of $REPEAT"
echo
echo "| run | job s | wall s | triangles | bricks read | MB read per rank | mesh MB written per rank | KB sent welding per rank |"
echo "|---|---|---|---|---|---|---|---|"
for t in 1 2; do
    files=(); walls=()
    for k in $(seq "$REPEAT"); do
        read -r w peak < <(measure "$V" extract "$S" --iso 600.5 --cold --threads $t --quiet -o "$TMP/one.ply" --force --stats "$TMP/o$t.$k.json")
        files+=("$TMP/o$t.$k.json"); walls+=("$w")
    done
    row "vdiso, $t thread$([ $t = 1 ] || echo s)" "$(median "${walls[@]}")" "${files[@]}"
done
for n in 1 2 4; do
    files=(); walls=()
    for k in $(seq "$REPEAT"); do
        read -r w peak < <(measure mpirun --oversubscribe -np $n "$M" extract "$S" --iso 600.5 --cold --quiet -o "$TMP/m.ply" --force --stats "$TMP/m$n.$k.json")
        files+=("$TMP/m$n.$k.json"); walls+=("$w")
    done
    row "vdiso-mpi, $n rank$([ $n = 1 ] || echo s)" "$(median "${walls[@]}")" "${files[@]}"
done
cmp -s "$TMP/one.ply" "$TMP/m.ply" && echo && echo "(the 4-rank PLY is the single process's, byte for byte)"
echo

echo "## 3. SAGE, normal view at 1024x1024, cold, full resolution (--lod-error 0), median of $REPEAT"
echo
echo "| run | job s (vdiso: + tree) | wall s | triangles | bricks read | busiest rank's | MB read | coverage MB per rank | MB gathered |"
echo "|---|---|---|---|---|---|---|---|---|"
SAGE=(--iso 600.5 --method sage --size 1024x1024 --lod-error 0 --cold --quiet --force)
for t in 1 2; do
    files=(); walls=()
    for k in $(seq "$REPEAT"); do
        read -r w peak < <(measure "$V" extract "$S" "${SAGE[@]}" --threads $t --stats "$TMP/s$t.$k.json" --png "$TMP/one$t.png")
        files+=("$TMP/s$t.$k.json"); walls+=("$w")
    done
    row "vdiso, $t thread$([ $t = 1 ] || echo s)" "$(median "${walls[@]}")" "${files[@]}"
done
for p in image object; do
    for n in 1 2 4; do
        files=(); walls=()
        for k in $(seq "$REPEAT"); do
            read -r w peak < <(measure mpirun --oversubscribe -np $n "$M" extract "$S" "${SAGE[@]}" --partition $p --stats "$TMP/$p$n.$k.json" --png "$TMP/$p$n.png")
            files+=("$TMP/$p$n.$k.json"); walls+=("$w")
        done
        row "vdiso-mpi by $p, $n rank$([ $n = 1 ] || echo s)" "$(median "${walls[@]}")" "${files[@]}"
    done
done
echo
for p in image object; do
    echo "picture of 4 ranks by $p against vdiso's: $("$V" compare "$TMP/one1.png" "$TMP/${p}4.png")"
done
