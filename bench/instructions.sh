#!/usr/bin/env bash
# Instructions a kept triangle costs on SAGE's warm frames, by stage: counted by valgrind's
# callgrind, so the same build and data give the same figures on a busy machine (where
# frame times of one view moved by half between runs of the same binary). For A/B of changes
# to the per-cell path; a count is not a time (branch mispredictions and the divider's latency
# cost time without instructions: confirm a gain with bench/ab_frames.sh).
#
# Frames 1..FRAMES of `vdiso extract STORE --iso ISO --method sage --view VIEW --path
# orbit:FRAMES+1` at 1024x1024, 1 thread: the run of frame 0 alone is subtracted, so reading,
# decoding and start-up fall out. Stages are functions' inclusive counts:
#   coverage     PolygonCoverage::cover (polygon rectangles, queries, scan conversion, the
#                rounding check)
#   corners      CornerProjection::project (a meta-cell's crossed cells' corners)
#   normals      BrickKernel::edgeNormal (the kept cells' vertex normals)
#   classify     BrickKernel::classifyCorners
#   meta-cell    the rest of extractShownMetaCell: per-cell tests, polygon outlines and
#                placing, vertices and triangles, the loop
#   outside      the rest of the traversal: the tree and meta-cell walks and their box tests
#
#   bench/instructions.sh STORE ISO VIEW [FRAMES] [BINARY...]    FRAMES default 4; BINARY
#                                                                default build/bin/vdiso
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh bench
store=$1 iso=$2 view=$3 frames=${4:-4}
shift $(( $# < 4 ? $# : 4 ))
binaries=("$@")
[ ${#binaries[@]} -gt 0 ] || binaries=("${BUILD_DIR:-build}/bin/vdiso")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Callgrind's inclusive count per function, and the run's --stats lines.
count() {
  local binary=$1 orbit=$2 out=$3
  valgrind --tool=callgrind --callgrind-out-file="$out.cg" "$binary" extract "$store" --iso "$iso" --method sage \
    --view "$view" --path "orbit:$orbit" --size 1024x1024 --threads 1 --quiet --stats - >"$out.stats" 2>"$out.log"
  callgrind_annotate --inclusive=yes --threshold=100 "$out.cg" >"$out.functions"
}
for binary in "${binaries[@]}"; do
  count "$binary" 1 "$work/one"
  count "$binary" $((frames + 1)) "$work/all"
  python3 - "$work" "$binary" "$store" "$iso" "$view" <<'PY'
import json, re, sys
work, binary, store, iso, view = sys.argv[1:]
stages = {"coverage": r"vdiso::PolygonCoverage::cover\(", "corners": r"vdiso::CornerProjection::project\(",
          "normals": r"BrickKernel<.*>::edgeNormal\(", "classify": r"BrickKernel<.*>::classifyCorners\(",
          "meta-cells": r"vdiso::extractShownMetaCell<", "traversal": r"ViewTraversal::run\(\)"}
def counts(name):
    total, found, seen = 0, {k: 0 for k in stages}, set()
    for line in open(f"{work}/{name}.functions"):
        m = re.match(r"\s*([\d,]+) \([\s\d.]+%\)\s+(.*)", line)
        if not m:
            continue
        n, function = int(m.group(1).replace(",", "")), m.group(2)
        if "PROGRAM TOTALS" in function:
            total = n
        for k, pattern in stages.items():
            if re.search(pattern, function) and "'" not in function.split("(")[0]:
                found[k] += n
                seen.add(k)
    return total, found, seen
(t1, one, _), (t2, all_, seen) = counts("one"), counts("all")
for k in ("meta-cells", "traversal"):
    if k not in seen:
        sys.exit(f"bench/instructions.sh: {binary} has no function for '{k}' ({stages[k]}): not a SAGE run of this build?")
frames = [json.loads(l) for l in open(f"{work}/all.stats")][1:]
triangles = sum(f["triangles"] for f in frames)
d = {k: (all_[k] - one[k]) / triangles for k in stages}
rest = d["meta-cells"] - d["coverage"] - d["corners"] - d["normals"] - d["classify"]
# A stage whose function the compiler inlined has no count of its own: its instructions are in
# the meta-cell rest, and it is said so rather than shown as 0.
shown = {k: f"{d[k]:.0f}" if k in seen else "inlined (in the rest)" for k in stages}
print(f"{binary}  {store} {iso} {view}: {len(frames)} warm frames, {triangles / len(frames):.0f} triangles a frame, "
      f"{(t2 - t1) / triangles:.0f} instructions a kept triangle: coverage {shown['coverage']}, corners {shown['corners']}, "
      f"normals {shown['normals']}, classify {shown['classify']}, meta-cell rest {rest:.0f}, "
      f"outside meta-cells {d['traversal'] - d['meta-cells']:.0f}")
PY
done
