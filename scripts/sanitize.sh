#!/usr/bin/env bash
# The whole test suite under AddressSanitizer and UndefinedBehaviorSanitizer (the build in
# build-fuzz/, scripts/build_sanitized.sh): any report fails the run.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build_sanitized.sh vdiso vdiso_tests
scripts/fetch_data.sh
export VDISO_DATA_DIR="$PWD/data"
# allocator_may_return_null: an allocation beyond what the machine has throws std::bad_alloc,
# as it does without ASan (the code turns that into a message naming the input).
export ASAN_OPTIONS=halt_on_error=1:detect_leaks=1:allocator_may_return_null=1
export LSAN_OPTIONS=suppressions=$PWD/tests/lsan.supp
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
# llvmpipe renders on the calling thread: its worker threads, alive until exit in a process that
# drew a picture (the OSMesa context is kept), sometimes crash LeakSanitizer's exit-time thread
# stop ("Tracer caught signal 11") when tests run side by side (3 of 10 runs of the CLI tests
# beside others; none of 8 with this).
export LP_NUM_THREADS=0
cd build-fuzz
ctest --output-on-failure -j "$(nproc)"
