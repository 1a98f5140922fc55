#!/usr/bin/env bash
# Runs every fuzz target (fuzz/README.md) for SECONDS each (default 30), from the committed
# seeds, in the sanitizer build (clang, ASan + UBSan, libFuzzer) in build-fuzz/, as many at a
# time as there are cores. Exits non-zero on any finding, in the target's process or in a helper
# process it forked (GDCM's, libhdf5's): a crash, a sanitizer report, a leak, a timeout, an
# out-of-memory, an abort. A target's finding is its non-zero exit or any file libFuzzer left in
# build-fuzz/findings/TARGET/ besides the run's log (the input that did it, to turn into a test).
# First the gate's self-test shows that it fails on each way a helper can die.
#
#   scripts/fuzz.sh [SECONDS] [TARGET ...]
#   VDISO_FUZZ_MERGE=1 scripts/fuzz.sh 600   # also merge inputs that add coverage into the seeds
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(nrrd nifti raw tiff dicom metaimage hdf5 zarr store camera_json protocol remote)
scripts/setup.sh
scripts/build_sanitized.sh "${targets[@]/#/fuzz_}" fuzz_helper_selftest

# gate NAME FINDINGS_DIR -- FUZZER ARGS...: runs the fuzzer, then says whether anything was
# found; 0 when nothing was. The log is FINDINGS_DIR/log.txt.
gate() {
  local name=$1 findings=$2
  shift 3
  rm -rf "$findings"
  mkdir -p "$findings"
  local status=0
  "$@" -artifact_prefix="$findings/" > "$findings/log.txt" 2>&1 || status=$?
  local artifacts
  artifacts=$(find "$findings" -type f ! -name log.txt | wc -l)
  if [ "$status" -ne 0 ] || [ "$artifacts" -ne 0 ]; then
    echo "fuzz: $name: exit status $status, $artifacts input(s) left in $findings" >&2
    return 1
  fi
}

# The self-test: each input makes the self-test helper die in one way (fuzz/fuzz_helper_selftest.cpp).
selftest() {
  local dir kind
  dir=$(mktemp -d)
  for kind in H S M X A; do
    printf '%s' "$kind" > "$dir/input_$kind"
    if gate "selftest $kind" "$dir/findings_$kind" -- build-fuzz/bin/fuzz_helper_selftest \
         -rss_limit_mb=2048 -malloc_limit_mb=2048 -timeout=10 "$dir/input_$kind" 2>/dev/null; then
      found=no
    else
      found=yes
    fi
    # A: a contained abort, accepted on purpose; every other end is a finding.
    if { [ "$kind" = A ] && [ "$found" = yes ]; } || { [ "$kind" != A ] && [ "$found" = no ]; }; then
      echo "fuzz: the gate's self-test failed: input '$kind' gave found=$found" >&2
      tail -30 "$dir/findings_$kind/log.txt" >&2
      rm -rf "$dir"
      exit 1
    fi
  done
  rm -rf "$dir"
  echo "fuzz: the gate's self-test: a helper's heap overflow, segfault, out-of-memory and silent exit are findings; its abort is accepted" >&2
}
selftest

run() {
  local t=$1 work
  work=$(mktemp -d)
  # New inputs go to a scratch corpus; the committed seeds are read only.
  if gate "$t" "build-fuzz/findings/$t" -- build-fuzz/bin/fuzz_$t "$work" fuzz/corpus/$t \
       -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=2048 \
       -print_final_stats=1; then
    grep -E "^stat::number_of_executed_units" "build-fuzz/findings/$t/log.txt" | sed "s/^/fuzz: $t: /" >&2 || true
    if [ "${VDISO_FUZZ_MERGE:-0}" = 1 ]; then
      build-fuzz/bin/fuzz_$t -merge=1 fuzz/corpus/$t "$work" > "build-fuzz/findings/$t/merge.txt" 2>&1 || true
      grep -E "MERGE-OUTER: [0-9]+ new files" "build-fuzz/findings/$t/merge.txt" | sed "s/^/fuzz: $t: /" >&2 || true
    fi
    rm -rf "$work"
    return 0
  fi
  tail -40 "build-fuzz/findings/$t/log.txt" >&2
  rm -rf "$work"
  return 1
}

jobs=$(nproc)
failed=()
pids=()
names=()
for t in "${targets[@]}"; do
  echo "fuzz: $t for $seconds s" >&2
  run "$t" &
  pids+=($!)
  names+=("$t")
  if [ ${#pids[@]} -ge "$jobs" ]; then
    wait "${pids[0]}" || failed+=("${names[0]}")
    pids=("${pids[@]:1}")
    names=("${names[@]:1}")
  fi
done
for i in "${!pids[@]}"; do
  wait "${pids[$i]}" || failed+=("${names[$i]}")
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: findings in ${failed[*]} (inputs in build-fuzz/findings/)" >&2
  exit 1
fi
echo "fuzz: ${#targets[@]} targets, $seconds s each, nothing found" >&2
