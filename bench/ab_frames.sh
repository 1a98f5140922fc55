#!/usr/bin/env bash
# A/B of vdiso binaries on warm frames: for each binary, the summed extract_s of frames 1..19 of
# `vdiso extract --method sage --path orbit:20` at 1024x1024 (frame 0 reads the bricks), the
# least of ROUNDS (default 3) rounds run alternately, so that the machine's moods fall on all. For measuring one
# change at a time (copy the binary built before and after it).
#
#   bench/ab_frames.sh STORE ISO VIEW BINARY...      THREADS=N (default 1)
set -euo pipefail
store=$1 iso=$2 view=$3
shift 3
for round in $(seq "${ROUNDS:-3}"); do
  for binary in "$@"; do
    "$binary" extract "$store" --iso "$iso" --method sage --view "$view" --path orbit:20 --size 1024x1024 \
      --threads "${THREADS:-1}" --quiet --stats - |
      python3 -c '
import json, sys
frames = [json.loads(line)["extract_s"] for line in sys.stdin if line.strip()]
print(sys.argv[1], round(sum(frames[1:]), 4))' "$binary"
  done
done | awk '{ if (!($1 in best) || $2 < best[$1]) best[$1] = $2 } END { for (b in best) print b, best[b] }'
