#!/usr/bin/env bash
# The main job end to end on the real default dataset: install, build, fetch the MRI head,
# convert it into a brick store, describe it, extract its surface, render it, print statistics.
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
echo
echo "== extract the surface (iso 40.5: the brain of this skull-stripped MRI) and render it"
$vdiso extract data/ch2better.vdiso --iso 40.5 --method octree -o data/ch2better.ply \
  --png data/ch2better_octree.png --view normal --stats data/ch2better_octree.json --force
cat data/ch2better_octree.json
echo
echo "== the head with its skin (data/ch2.nii.gz, iso 40.5)"
$vdiso convert data/ch2.nii.gz data/ch2.vdiso --force
$vdiso extract data/ch2.vdiso --iso 40.5 --png data/ch2_skin.png --stats - --force
echo
echo "pictures: data/ch2better_octree.png data/ch2_skin.png   mesh: data/ch2better.ply"
