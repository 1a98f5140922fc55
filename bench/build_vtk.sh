#!/usr/bin/env bash
# Builds the given targets in build-vtk/, the Release build with the VTK comparison programs
# (VDISO_BUILD_VTK_COMPARE=ON; needs libvtk9-dev). Quiet; on failure, shows what the tools
# said. Used by the bench scripts that compare against VTK.
#
#   bench/build_vtk.sh TARGET...       JOBS=N for the build's parallelism (default 2)
set -euo pipefail
cd "$(dirname "$0")/.."
log=$(mktemp)
trap 'rm -f "$log"' EXIT
if ! { cmake -S . -B build-vtk -DCMAKE_BUILD_TYPE=Release -DVDISO_BUILD_VTK_COMPARE=ON -DVDISO_BUILD_TESTS=OFF &&
       cmake --build build-vtk -j "${JOBS:-2}" --target "$@"; } > "$log" 2>&1; then
  cat "$log" >&2
  exit 1
fi
