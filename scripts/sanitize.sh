#!/usr/bin/env bash
# The whole test suite under AddressSanitizer and UndefinedBehaviorSanitizer (the build in
# build-fuzz/, scripts/build_sanitized.sh): any report fails the run.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build_sanitized.sh vdiso vdiso_tests
scripts/fetch_data.sh
export VDISO_DATA_DIR="$PWD/data"
export ASAN_OPTIONS=halt_on_error=1:detect_leaks=1:abort_on_error=0
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
cd build-fuzz
ctest --output-on-failure -j "$(nproc)"
