#!/usr/bin/env bash
# Runs every fuzz target (fuzz/README.md) for SECONDS each (default 30), from the committed
# seeds, in the sanitizer build (clang, ASan + UBSan, libFuzzer) in build-fuzz/. Exits non-zero
# on any finding: a crash, a sanitizer report, a leak, a timeout, an abort. What a target found
# is left in build-fuzz/findings/TARGET/ (the input that did it, to turn into a test).
#
#   scripts/fuzz.sh [SECONDS] [TARGET ...]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(nrrd nifti raw tiff dicom metaimage hdf5 zarr store camera_json protocol)
scripts/setup.sh
scripts/build_sanitized.sh "${targets[@]/#/fuzz_}"
failed=()
for t in "${targets[@]}"; do
  work=$(mktemp -d)
  findings=build-fuzz/findings/$t
  mkdir -p "$findings"
  echo "fuzz: $t for $seconds s" >&2
  # New inputs go to a scratch corpus; the committed seeds are read only.
  if ! build-fuzz/bin/fuzz_$t "$work" fuzz/corpus/$t -max_total_time="$seconds" -timeout=10 \
       -rss_limit_mb=2048 -malloc_limit_mb=2048 -artifact_prefix="$findings/" -print_final_stats=1 \
       > "$findings/log.txt" 2>&1; then
    failed+=("$t")
    tail -40 "$findings/log.txt" >&2
  else
    grep -E "^stat::number_of_executed_units" "$findings/log.txt" | sed "s/^/fuzz: $t: /" >&2 || true
  fi
  rm -rf "$work"
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: findings in ${failed[*]} (inputs in build-fuzz/findings/)" >&2
  exit 1
fi
echo "fuzz: ${#targets[@]} targets, $seconds s each, nothing found" >&2
