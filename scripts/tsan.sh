#!/usr/bin/env bash
# ThreadSanitizer over the threaded serve code (the frame pool with its nested passes, follow
# mode's fan-out, shared chunks, the sessions): builds the tests with clang -fsanitize=thread in
# build-tsan/ and runs those suites. Debian's TBB is not instrumented, so reports whose stacks
# pass through TBB (the test volumes' generator) are left out; any other report fails. Not in
# CI (a third build); run it after changing serve/, io/remote/ or core/extract/'s threading (the
# remote suites: scripts/tsan.sh 'TransferLoop.*:Remote*').
#
#   scripts/tsan.sh [GTEST_FILTER]
set -euo pipefail
cd "$(dirname "$0")/.."
filter=${1:-'FramePool.*:ServeFollow.*:ServeServer.ViewersShare*:ServeServer.ThreadsDo*:ServeServer.AHeavy*:ServeSession.*:SharedChunks.*'}
cmake -S . -B build-tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" \
  -DCMAKE_CXX_FLAGS=-fsanitize=thread -DCMAKE_C_FLAGS=-fsanitize=thread -DCMAKE_EXE_LINKER_FLAGS=-fsanitize=thread \
  -DCMAKE_SHARED_LINKER_FLAGS=-fsanitize=thread -DVDISO_BUILD_BENCH=OFF >/dev/null
cmake --build build-tsan -j "$(nproc)" --target vdiso_tests
log=$(mktemp)
reports=$(mktemp -d)
trap 'rm -rf "$log" "$reports"' EXIT
# Every process's reports go to files (log_path): tests that run the vdiso command (the remote
# suites) get theirs too, and exitcode=0 keeps a report in such a child from failing its test.
TSAN_OPTIONS="halt_on_error=0 exitcode=0 second_deadlock_stack=1 log_path=$reports/tsan" \
  build-tsan/bin/vdiso_tests --gtest_filter="$filter" >"$log" 2>&1 || true
/usr/bin/python3 - "$log" "$reports" <<'PY'
import glob, os, re, sys
text = open(sys.argv[1]).read()
reports = []
for name in glob.glob(os.path.join(sys.argv[2], "tsan*")):
    reports += open(name, errors="replace").read().split("WARNING: ThreadSanitizer")[1:]
ours = [r for r in reports if "tbb::" not in r and "libtbb" not in r]
result = re.findall(r"\[  (?:PASSED|FAILED)  \].*", text)
print(f"tsan: {len(reports)} reports, {len(ours)} outside TBB; tests: {' '.join(result)}")
for r in ours[:5]:
    print("WARNING: ThreadSanitizer" + r[:3000])
sys.exit(1 if ours or not result or "FAILED" in result[0] else 0)
PY
