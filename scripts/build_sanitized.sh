#!/usr/bin/env bash
# Configures and builds the sanitizer build in build-fuzz/: clang, ASan + UBSan (with
# float-cast-overflow, halting on the first report), libFuzzer's instrumentation, the tests and
# the fuzz targets. Arguments name targets to build (default: all).
set -euo pipefail
cd "$(dirname "$0")/.."
# -O1 with line tables only: sanitizer reports keep their file:line, and the build is about a
# third faster than with full debug information (it runs in CI beside the Release build).
generator=()
[ -f build-fuzz/CMakeCache.txt ] || generator=(-G Ninja)  # as scripts/build.sh
cmake -S . -B build-fuzz "${generator[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
  -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" \
  -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" -DVDISO_FUZZ=ON -DVDISO_BUILD_BENCH=OFF >/dev/null
if [ $# -gt 0 ]; then
  cmake --build build-fuzz -j "$(nproc)" --target "$@"
else
  cmake --build build-fuzz -j "$(nproc)"
fi
