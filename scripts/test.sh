#!/usr/bin/env bash
# Installs what is missing, builds, fetches the real dataset, runs every test with ctest; then
# the same tests under AddressSanitizer and UndefinedBehaviorSanitizer (scripts/sanitize.sh),
# and every fuzz target for 3 s (scripts/fuzz.sh: longer runs by hand). VDISO_QUICK=1 runs the first part only.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
scripts/fetch_data.sh
export VDISO_DATA_DIR="$PWD/data"
cd build
ctest --output-on-failure -j "$(nproc)"
cd ..
if [ "${VDISO_QUICK:-0}" != 1 ]; then
  scripts/sanitize.sh
  scripts/fuzz.sh 3
fi
