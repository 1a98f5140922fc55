#!/usr/bin/env bash
# Installs the Debian packages vdiso builds against, only those missing: `demo`, what the
# command and the Python module need; no argument, everything the tests need; `bench`, also VTK.
# Uses sudo when not root. Safe to run again: does nothing when everything is there.
set -euo pipefail

# What the vdiso command and the Python module build against and run with: all the demo needs
# (`scripts/setup.sh demo`), all but the reader modules' libraries.
packages=(
  build-essential cmake ninja-build pkg-config
  libglm-dev libtbb-dev zlib1g-dev libzstd-dev liblz4-dev libpng-dev
  libdeflate-dev                          # CRC-32 of stored bytes (io/crc32.h)
  libosmesa6-dev nlohmann-json3-dev
  libboost-dev libmeshoptimizer-dev       # vdiso serve: Beast (HTTP, WebSocket), geometry codecs
  libtiff-dev                             # TIFF stacks (io/readers/tiff_reader.h)
  libblosc-dev                            # Zarr chunks (io/readers/zarr_array.h)
  libcurl4-openssl-dev                    # remote stores over HTTP(S) and S3 (io/remote)
  pybind11-dev python3-dev python3-numpy  # the Python module (python/)
)
# Everything else (`scripts/setup.sh`, what scripts/test.sh runs): the tests, the benchmarks'
# own programs, vdiso-mpi, the sanitizer and fuzz builds, the servers and the browser the tests
# run against, and the viewer's modules.
profile=${1:-all}
if [ "$profile" != demo ]; then
  packages+=(
    # The reader modules (-DVDISO_READER_MODULES, on but in the demo, which reads NIfTI):
    libopenvdb-dev libboost-iostreams-dev   # OpenVDB; its Find module needs boost-iostreams and TBB
    libgdcm-dev                             # DICOM series (io/readers/dicom_reader.h)
    libhdf5-dev                             # HDF5 datasets (io/readers/hdf5_reader.h)
    libgtest-dev libbenchmark-dev
    chromium                                # the viewer's end-to-end test (headless)
    libjpeg-turbo-progs                     # bench/serve.sh: JPEG sizes of frames
    clang libclang-rt-dev                   # the sanitizer build and the fuzz targets (libFuzzer)
    libopenmpi-dev openmpi-bin              # vdiso-mpi (mpi/): built only when MPI is found
    nginx-light python3-botocore curl openssl   # the remote stores' test servers (tests/remote/)
    python3-pytest python3-skimage python3-scipy python3-zarr python3-dask python3-distributed python3-meshio   # the Python module's tests (scipy: marching_cubes' topology tests)
  )
fi
# `scripts/setup.sh bench`: also what the benchmarks compare against (VTK's Flying Edges from
# Python, for bench/python.sh and bench/real_scans.sh) and count with (valgrind's callgrind, for
# bench/instructions.sh), which the build and tests do not need.
if [ "$profile" = bench ]; then
  packages+=(python3-vtk9 valgrind)
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# npm comes with Debian's nodejs from its own package (a machine may have a newer nodejs with
# npm built in: then nothing is installed).
[ "$profile" = demo ] || command -v npm >/dev/null 2>&1 || missing+=(nodejs npm)

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}" >&2
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# The viewer's modules (three.js, meshoptimizer's decoder, puppeteer-core for its test), at the
# versions web/package-lock.json pins; again only when the lock file is newer than the install.
[ "$profile" != demo ] || exit 0
cd "$(dirname "$0")/../web"
if [ ! -f node_modules/.package-lock.json ] || [ package-lock.json -nt node_modules/.package-lock.json ]; then
  echo "setup: npm ci in web/" >&2
  npm ci --no-audit --no-fund --loglevel=error >/dev/null
fi
