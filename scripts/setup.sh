#!/usr/bin/env bash
# Installs the Debian packages vdiso builds against, only those missing.
# Uses sudo when not root. Safe to run again: does nothing when everything is there.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libglm-dev libtbb-dev zlib1g-dev libzstd-dev liblz4-dev libpng-dev
  libopenvdb-dev libboost-iostreams-dev   # OpenVDB's Find module needs boost-iostreams and TBB
  libosmesa6-dev nlohmann-json3-dev
  libgtest-dev libbenchmark-dev
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
echo "setup: installing ${missing[*]}" >&2
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
