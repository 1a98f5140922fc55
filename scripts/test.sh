#!/usr/bin/env bash
# Installs what is missing, builds, fetches the real dataset, runs every test with ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
scripts/fetch_data.sh
export VDISO_DATA_DIR="$PWD/data"
cd build
ctest --output-on-failure -j "$(nproc)"
