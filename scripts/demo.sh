#!/usr/bin/env bash
# The main job end to end on the real default dataset: install, build, fetch the MRI head,
# convert it into a brick store, describe it, extract its surface, render it, print statistics.
set -euo pipefail
cd "$(dirname "$0")/.."
# Only what the demo runs is installed and built: the command and the Python module, without
# the DICOM, HDF5 and OpenVDB reader modules (the demo reads NIfTI; a command that needs one says
# so). scripts/setup.sh and scripts/build.sh install and build everything.
scripts/setup.sh demo
scripts/build.sh -DVDISO_BUILD_TESTS=OFF -DVDISO_BUILD_BENCH=OFF -DVDISO_BUILD_MPI=OFF -DVDISO_READER_MODULES=OFF \
  --target vdiso _vdiso
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
echo "== only what the camera sees: SAGE on the same view, and how much of the picture it keeps"
$vdiso extract data/ch2better.vdiso --iso 40.5 --method sage --view normal \
  --png data/ch2better_sage.png --stats data/ch2better_sage.json --force
cat data/ch2better_sage.json
$vdiso compare data/ch2better_octree.png data/ch2better_sage.png
echo
echo "== the head with its skin (data/ch2.nii.gz, iso 40.5): full surface and SAGE, distant view"
$vdiso convert data/ch2.nii.gz data/ch2.vdiso --force
$vdiso extract data/ch2.vdiso --iso 40.5 --png data/ch2_skin.png --stats - --force
$vdiso extract data/ch2.vdiso --iso 40.5 --method octree --view distant --png data/ch2_distant_octree.png --force --quiet
$vdiso extract data/ch2.vdiso --iso 40.5 --method sage --view distant --png data/ch2_distant_sage.png --stats - --force
$vdiso compare data/ch2_distant_octree.png data/ch2_distant_sage.png
echo
echo "== from Python (PYTHONPATH=build/python /usr/bin/python3): the same MRI's store, the visible surface"
PYTHONPATH="$PWD/build/python" /usr/bin/python3 - <<'PY'
import vdiso
store = vdiso.open("data/ch2better.vdiso")
mesh = store.extract(40.5, method="sage", view="normal")
print(store, "->", mesh, f"in {mesh.stats['extract_s']:.3f} s")
PY
PYTHONPATH="$PWD/build/python" /usr/bin/python3 examples/quickstart.py data
echo
echo "pictures: data/ch2better_octree.png data/ch2better_sage.png data/ch2_skin.png"
echo "          data/ch2_distant_octree.png data/ch2_distant_sage.png   mesh: data/ch2better.ply"
