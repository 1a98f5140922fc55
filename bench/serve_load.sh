#!/usr/bin/env bash
# One `vdiso serve` shared by many viewers (issue: many viewers, one server): 1 to 64 viewers
# orbiting the MRI (ch2better) and the generated 1024^3 head on this machine's cores, each
# sending its next camera when its frame ends; from halfway, 8 more join one at a time
# (vdiso_serve_load, a server and C++ clients of docs/protocol.md in one process; the clients
# keep chunks undecoded, so that the CPU, threads and memory measured are the server's). Then 32 viewers again with no shared
# chunks (--chunk-cache-mb 0), to see what sharing buys; then one leader orbiting with 8
# followers (follow mode): how much later than the leader's each follower's copy of a frame ends.
#
#   bench/serve_load.sh [SECONDS] [VIEWERS...]     default 15 s a run; 1 4 8 16 32 64
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-15}
shift || true
counts=("$@")
[ ${#counts[@]} -gt 0 ] || counts=(1 4 8 16 32 64)
build=${BUILD_DIR:-build}
cmake --build "$build" -j2 --target vdiso vdiso_serve_load > /dev/null
vdiso=$build/bin/vdiso
scripts/fetch_data.sh
mkdir -p data/bench
[ -f data/bench/ch2better.vdiso ] || $vdiso convert data/ch2better.nii.gz data/bench/ch2better.vdiso --quiet
if [ ! -f data/bench/head1024.vdiso ]; then
  [ -f data/bench/head1024.raw ] || $vdiso synth data/bench/head1024.raw --kind head --size 1024 --quiet
  $vdiso convert data/bench/head1024.raw data/bench/head1024.vdiso --dims 1024,1024,1024 --type u16 --quiet
fi
rows=$(mktemp)
trap 'rm -f "$rows"' EXIT
run() {  # store iso viewers extra...
  local store=$1 iso=$2 n=$3; shift 3
  $build/bin/vdiso_serve_load "data/bench/$store" --iso "$iso" --viewers "$n" --seconds "$seconds" "$@" >> "$rows"
}
for spec in "ch2better.vdiso 40.5" "head1024.vdiso 600.5"; do
  set -- $spec
  for n in "${counts[@]}"; do run "$1" "$2" "$n"; done
  run "$1" "$2" 32 --chunk-cache-mb 0
  $build/bin/vdiso_serve_load "data/bench/$1" --iso "$2" --followers 8 --seconds "$seconds" >> "$rows"
done
python3 - "$rows" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
follows = [r for r in rows if "followers" in r]
rows = [r for r in rows if "followers" not in r]
print("| store | viewers | shared chunks MB | frame p50 / p95 / p99 ms | frames a viewer (min-max) | frames/s in all | joining viewers: coarse / final ms, median (p95) | server threads (process) | peak RSS MB | encodings per distinct chunk |")
print("|---|---|---|---|---|---|---|---|---|---|")
for r in rows:
    print(f"| {r['store']} | {r['viewers']} | {r['chunk_cache_mb']} | {r['frame_ms_p50']:.0f} / {r['frame_ms_p95']:.0f} / {r['frame_ms_p99']:.0f} | "
          f"{r['frames_min']}-{r['frames_max']} | {r['frames_per_s']:.1f} | {r['join_coarse_ms']:.0f} ({r['join_coarse_ms_p95']:.0f}) / {r['join_final_ms']:.0f} ({r['join_final_ms_p95']:.0f}) | "
          f"{r['server_threads_max']} ({r['threads_max']}) | {r['peak_rss_mb']:.0f} | {r['encodings_per_chunk']:.2f} ({r['chunks_encoded']} / {r['distinct_chunks']}) |")
print()
print("| store | followers | leader frames | passes a frame | frames each follower got | lag behind the leader p50 / p95 / max ms |")
print("|---|---|---|---|---|---|")
for r in follows:
    print(f"| {r['store']} | {r['followers']} | {r['leader_frames']} | {r['passes_per_frame']:.2f} | {r['frames_followed_min']}-{r['frames_followed_max']} | "
          f"{r['lag_ms_p50']:.1f} / {r['lag_ms_p95']:.1f} / {r['lag_ms_max']:.1f} |")
PY
