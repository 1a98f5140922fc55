#!/usr/bin/env bash
# Configures and builds vdiso in Release into build/ (binary: build/bin/vdiso).
# Extra arguments go to the CMake configure step (e.g. -DVDISO_BUILD_VTK_COMPARE=ON).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build build -j "$(nproc)"
