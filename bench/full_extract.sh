#!/usr/bin/env bash
# Full extraction (octree) into memory on real scans and the generated head, from the page
# cache: `vdiso extract STORE --iso I --method octree --threads T --stats -`, 1 and 2 threads
# in turn, pair by pair (the ratio is the median of the pairs' ratios). Per row: median
# extract_s, ns per triangle of extract_s, minor page faults and peak RSS of the process
# (/usr/bin/time), and the output's size (vertices and normals 24 B, triangles 12 B).
# With BASE=path/to/another/vdiso, each run of it follows the same run of this build's, and
# the table gains its figures and the ratio base / this (median of pairs): before and after.
# Data: data/cranium.nhdr (Debian's invesalius-examples CT; skin -423.5, bone 200.5),
# data/ch2better.nii.gz and data/ch2.nii.gz (mricron-data MRI, 40.5), and the 512^3 head
# (vdiso synth --kind head; skin 600.5, bone 1224.5); stores made as bench/real_scans.sh does.
#
#   bench/full_extract.sh [PAIRS]      default 7
set -euo pipefail
cd "$(dirname "$0")/.."
pairs=${1:-7}
build=${BUILD_DIR:-build}
vdiso=$build/bin/vdiso
base=${BASE:-}
py=/usr/bin/python3
vdiso=$vdiso bench/real_stores.sh
# One run: a JSON line of the stats with the process's page faults and peak RSS added.
run() {
  local bin=$1 store=$2 iso=$3 threads=$4 t
  t=$(mktemp)
  /usr/bin/time -f '%R %M' -o "$t" $bin extract "data/bench/$store.vdiso" --iso "$iso" --method octree \
    --threads "$threads" --stats - --quiet | $py -c "
import json, sys
s = json.loads(sys.stdin.read()); faults, rss = open('$t').read().split()[-2:]
s.update(faults=int(faults), rss_mb=int(rss) / 1024, bin='$bin'); print(json.dumps(s))"
  rm -f "$t"
}
echo "| scan | iso | threads | triangles | output MB | extract s | ns / triangle | 2 threads / 1 | page faults / output MB | peak RSS MB |${base:+ before s | before / after | before faults / output MB | before peak RSS MB |}"
echo "|---|---|---|---|---|---|---|---|---|---|${base:+---|---|---|---|}"
for spec in "cranium -423.5" "cranium 200.5" "ch2better 40.5" "ch2 40.5" "head512 600.5" "head512 1224.5"; do
  set -- $spec
  for _ in $(seq "$pairs"); do
    for threads in 1 2; do
      run "$vdiso" "$1" "$2" $threads
      [ -z "$base" ] || run "$base" "$1" "$2" $threads
    done
  done | $py -c "
import json, statistics, sys
rows = [json.loads(l) for l in sys.stdin]
med = statistics.median
def runs(bin, t): return [r for r in rows if r['bin'] == bin and r['threads'] == t]
this, base = '$vdiso', '$base'
one = runs(this, 1)
for t in (1, 2):
    r = runs(this, t)
    tri, verts = r[0]['triangles'], r[0]['vertices']
    out_mb = (verts * 24 + tri * 12) / 1e6
    s = med(x['extract_s'] for x in r)
    ratio = f\"{med(a['extract_s'] / b['extract_s'] for a, b in zip(one, r)):.2f}x\" if t == 2 else ''
    line = (f\"| {sys.argv[1]} | {sys.argv[2]} | {t} | {tri} | {out_mb:.1f} | {s:.4f} | {s / tri * 1e9:.1f} | {ratio} | \"
            f\"{med(x['faults'] for x in r) / out_mb:.0f} | {med(x['rss_mb'] for x in r):.0f} |\")
    if base:
        b = runs(base, t)
        line += (f\" {med(x['extract_s'] for x in b):.4f} | {med(p['extract_s'] / q['extract_s'] for p, q in zip(b, r)):.2f}x | \"
                 f\"{med(x['faults'] for x in b) / out_mb:.0f} | {med(x['rss_mb'] for x in b):.0f} |\")
    print(line)
" "$1" "$2"
done
