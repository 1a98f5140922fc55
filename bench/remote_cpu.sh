#!/usr/bin/env bash
# vdiso's CPU a request and its threads on a remote view, two builds interleaved: each round runs
# the view through the link (bench/bucket_server.sh: nginx behind the link proxy, DELAY_MS and
# RATE_MBIT), then the same view of the same file from the page cache, with each build in turn.
# CPU a request = (remote CPU - local CPU) / the remote run's requests (user + sys, whole process).
# Threads: the most the process had, sampled every 2 ms.
#
#   bench/remote_cpu.sh BASE_VDISO NEW_VDISO [RUNS] [VIEW] [NAME.vdiso] [ISO] [DELAY_MS] [RATE_MBIT]
#   (defaults: 7 rounds, normal, head2560.vdiso from data/bench/bucket/, 600.5, 20, 1000)
set -euo pipefail
cd "$(dirname "$0")/.."
base=$1
new=$2
runs=${3:-7}
view=${4:-normal}
name=${5:-head2560.vdiso}
iso=${6:-600.5}
delay=${7:-20}
rate=${8:-1000}
store=data/bench/bucket/$name
[ -f "$store" ] || { echo "$store is missing (bench/remote.sh $name ... makes the bench stores)" >&2; exit 1; }
source bench/bucket_server.sh
start_bucket_server "$delay" "$rate"

# run BIN LOCATION [OPTIONS...] -> "wall cpu requests threads"
run() {
  local bin=$1 location=$2
  shift 2
  /usr/bin/time -f "%e %U %S" -o "$work/time" "$bin" extract "$location" "$@" --iso "$iso" --method sage \
    --view "$view" --size 1024x1024 --stats "$work/stats.json" --quiet --force -o "$work/out.ply" &
  local pid=$! most=0 child n
  while kill -0 $pid 2>/dev/null; do
    child=$(pgrep -P $pid | head -1 || true)
    if [ -n "$child" ]; then
      n=$(ls /proc/$child/task 2>/dev/null | wc -l || true)
      [ "$n" -gt "$most" ] && most=$n
    fi
    sleep 0.002
  done
  wait $pid
  python3 - "$work/time" "$work/stats.json" "$most" <<'EOF'
import json, sys
wall, user, system = open(sys.argv[1]).read().split()[-3:]
d = json.load(open(sys.argv[2]))
print(wall, float(user) + float(system), d.get("remote_requests", 0), sys.argv[3])
EOF
}

echo "| build | round | remote wall s | remote CPU s | requests | most threads | local CPU s | CPU a request ms |"
echo "|---|---|---|---|---|---|---|---|"
for r in $(seq "$runs"); do
  for label in base new; do
    bin=$base; [ $label = new ] && bin=$new
    read -r wall cpu requests threads < <(run "$bin" "s3://bucket/$name" "${remote[@]}")
    read -r _ localCpu _ _ < <(run "$bin" "$store")
    echo "| $label | $r | $wall | $cpu | $requests | $threads | $localCpu | $(python3 -c "print(round(1000 * ($cpu - $localCpu) / $requests, 3))") |"
  done
done | tee "$work/rows"
python3 - "$work/rows" <<'EOF'
import statistics, sys
rows = [l.strip("|\n").split("|") for l in open(sys.argv[1])]
for label in ("base", "new"):
    mine = [[c.strip() for c in r] for r in rows if r[0].strip() == label]
    col = lambda k: statistics.median(float(r[k]) for r in mine)
    print(f"{label}: medians of {len(mine)}: wall {col(2):.3f} s, CPU {col(3):.3f} s, requests {col(4):.0f}, "
          f"threads {col(5):.0f}, CPU a request {col(7):.3f} ms")
EOF
echo "($name, $view, sage, 1024x1024, $(nproc) cores, against $endpoint; local runs from the page cache)"
