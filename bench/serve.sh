#!/usr/bin/env bash
# vdiso serve on an orbit (issue: remote viewing): latency from the camera message to the first
# chunk and to the frame's end, and the bytes a frame costs against the alternatives, for the
# 1024^3 generated head and the real MRI, 1024x1024, 36 frames of 10 degrees, 1 and 2 threads.
# Warm: a first client runs the orbit, a second is measured (brick cache warm, chunk cache
# empty at its first frame). Cold: the page cache dropped, the first frame of a fresh server.
#
#   bench/serve.sh [FRAMES]      (default 36; makes data/head1024.vdiso and the MRI store
#                                 if missing; root for the cold run)
set -euo pipefail
cd "$(dirname "$0")/.."
frames=${1:-36}
bench=build/bin/vdiso_serve_bench
vdiso=build/bin/vdiso
[ -x $bench ] || scripts/build.sh
command -v cjpeg >/dev/null || { echo "needs cjpeg (scripts/setup.sh installs libjpeg-turbo-progs)"; exit 1; }
mkdir -p data
[ -f data/head1024.vdiso ] || $vdiso synth data/head1024.vdiso --kind head --size 1024
if [ ! -f data/ch2better.vdiso ]; then
  scripts/fetch_data.sh
  $vdiso convert data/ch2better.nii.gz data/ch2better.vdiso --quiet
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

summarise() {  # FILE: one markdown row of medians
  python3 - "$1" <<'EOF'
import json, statistics, sys
lines = [json.loads(l) for l in open(sys.argv[1])]
frames = [l for l in lines if "frame" in l]
s = [l for l in lines if l.get("summary")][0]
m = lambda key: statistics.median(f[key] for f in frames)
print("| %s | %d | %.1f | %.0f | %.1f | %.0f | %.0f | %.0f |" % (
    s["store"], s["threads"], m("server_first_chunk_ms"), m("server_complete_ms"),
    m("client_first_geometry_ms"), m("client_complete_ms"),
    max(f["server_complete_ms"] for f in frames[1:]), frames[0]["server_complete_ms"]))
EOF
}

bytes_row() {  # FILE IMAGES_DIR: the bytes table's row
  for f in "$2"/frame*.ppm; do cjpeg -quality 90 "$f" > "${f%.ppm}.jpg"; done
  python3 - "$1" "$2" <<'EOF'
import json, os, statistics, sys
lines = [json.loads(l) for l in open(sys.argv[1])]
frames = [l for l in lines if "frame" in l]
s = [l for l in lines if l.get("summary")][0]
d = sys.argv[2]
png = statistics.median(os.path.getsize(os.path.join(d, f)) for f in os.listdir(d) if f.endswith(".png"))
jpg = statistics.median(os.path.getsize(os.path.join(d, f)) for f in os.listdir(d) if f.endswith(".jpg"))
step = statistics.median(f["bytes"] for f in frames[1:])
resend = statistics.median(f["whole_frame_bytes"] for f in frames[1:])
print("| %s | %.2f MB | %.0f KB (%.1f%%) | %.2f MB | %.2f MB | %.2f MB | %.0f KB | %.0f KB | %.2f | %d / %d / %d |" % (
    s["store"], s["first_frame_bytes"] / 1e6, step / 1e3, 100 * step / s["first_frame_bytes"],
    resend / 1e6, s["sage_frame_bytes"] / 1e6, s["full_surface_bytes"] / 1e6, png / 1e3, jpg / 1e3,
    s["bytes_per_triangle_first_frame"], s["first_frame_triangles"], s["sage_frame_triangles"],
    s["full_surface_triangles"]))
EOF
}

latency="| store | threads | first chunk, server ms | complete, server ms | first geometry, client ms | complete, client ms | slowest step, server ms | first frame, server ms |
|---|---|---|---|---|---|---|---|"
bytes="| store | first frame | median 10-degree step | same frame re-sent whole (median) | SAGE's own frame (per-cell tests) | full surface mesh | PNG of the frame | JPEG q90 | bytes per triangle, first frame | triangles: first frame / SAGE / full surface |
|---|---|---|---|---|---|---|---|---|---|"
for spec in "data/head1024.vdiso 600.5" "data/ch2better.vdiso 40.5"; do
  set -- $spec
  for threads in 1 2; do
    mkdir -p "$out/img"
    rm -f "$out/img"/*
    $bench "$1" --iso "$2" --size 1024 --frames "$frames" --threads $threads --images "$out/img" > "$out/run.jsonl"
    latency+=$'\n'"$(summarise "$out/run.jsonl")"
    [ $threads = 2 ] && bytes+=$'\n'"$(bytes_row "$out/run.jsonl" "$out/img")"
  done
done
echo "$latency"
echo
echo "$bytes"

if [ "$(id -u)" -eq 0 ]; then
  echo
  echo "| store | cold first frame: server ms | first chunk ms | bricks read | bytes |"
  echo "|---|---|---|---|---|"
  for spec in "data/head1024.vdiso 600.5" "data/ch2better.vdiso 40.5"; do
    set -- $spec
    sync
    echo 3 > /proc/sys/vm/drop_caches
    $bench "$1" --iso "$2" --size 1024 --frames 1 --threads 2 --no-warmup > "$out/cold.jsonl"
    python3 - "$out/cold.jsonl" "$1" <<'EOF'
import json, sys
f = [json.loads(l) for l in open(sys.argv[1]) if '"frame"' in l][0]
print("| %s | %.0f | %.1f | %d | %.2f MB |" % (sys.argv[2], f["server_complete_ms"], f["server_first_chunk_ms"], f["bricks_read"], f["bytes"] / 1e6))
EOF
  done
fi
