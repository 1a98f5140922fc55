#!/usr/bin/env bash
# vdiso serve on a store in a bucket: the first frames a fresh server gives a fresh client,
# cold (no warm-up orbit), the store read through bench/bucket_server.sh's endpoint (by default
# nginx behind tests/remote/link_proxy.cpp) holding each request DELAY_MS (public bucket). The server opens the store (header and
# index) before the client connects; the times are from the client's VIEW.
#
#   bench/remote_serve.sh NAME.vdiso [DELAY_MS] [ISO] [FRAMES] [RATE_MBIT]
#                                          (a store in data/bench/bucket/; RATE_MBIT 0: no cap)
set -euo pipefail
cd "$(dirname "$0")/.."
name=$1
delay=${2:-20}
iso=${3:-600.5}
frames=${4:-4}
rate=${5:-0}
source bench/bucket_server.sh
start_bucket_server "$delay" "$rate"
# The test server hashes the object once for its ETag (an object store has it stored).
build/bin/vdiso info "s3://bucket/$name" "${remote[@]}" --remote-timeout 900 > /dev/null
build/bin/vdiso_serve_bench "s3://bucket/$name" --iso "$iso" --frames "$frames" --size 1024 --no-warmup \
  --web web "${remote[@]}" > "$work/frames.json"
[ -n "${KEEP_JSON:-}" ] && cp "$work/frames.json" "$KEEP_JSON"
echo "| frame | coarse frame complete ms | first geometry ms | complete ms | bricks read | triangles |"
echo "|---|---|---|---|---|---|"
python3 - "$work/frames.json" <<'PY'
import json, sys
for line in open(sys.argv[1]):
    j = json.loads(line)
    if j.get("summary"):
        continue
    print("| %d | %.0f | %.0f | %.0f | %d | %d |" % (j["frame"], j["client_coarse_complete_ms"],
          j["client_first_geometry_ms"], j["client_complete_ms"], j["bricks_read"], j["triangles"]))
PY
echo "($name, against $endpoint, 1024x1024, the normal view's orbit, $(nproc) cores)"
