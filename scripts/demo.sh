#!/usr/bin/env bash
# The main job end to end on the real default dataset: install, build, fetch the MRI head,
# convert it into a brick store, describe it.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
scripts/fetch_data.sh
vdiso=build/bin/vdiso

echo "== convert the MRI head (data/ch2better.nii.gz) into a brick store"
$vdiso convert data/ch2better.nii.gz data/ch2better.vdiso --force
echo
echo "== the store"
$vdiso info data/ch2better.vdiso --iso 40.5
