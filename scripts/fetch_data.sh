#!/usr/bin/env bash
# Puts the real default dataset in data/: the MNI "Colin 27" MRI head templates from Debian's
# mricron-data package (ch2better.nii.gz, 301x370x316 u8; ch2.nii.gz, 181x217x181 u8, with
# skin), and the CT of Debian's invesalius-examples (Cranium.inv3: a gzip tar holding a
# 256x256x108 int16 volume in HU; data/cranium.nhdr names its samples, data/cranium.raw; skin
# at -423.5, bone at 200.5). The packages are downloaded and unpacked, not installed.
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p data
if [ -f data/ch2better.nii.gz ] && [ -f data/ch2.nii.gz ] && [ -f data/cranium.nhdr ]; then exit 0; fi

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
# apt-get download writes into the current directory; make it writable for apt's sandbox user.
chmod 777 "$tmp"
if ! (cd "$tmp" && apt-get download mricron-data invesalius-examples >/dev/null 2>&1); then
  $sudo apt-get update -qq
  (cd "$tmp" && apt-get download mricron-data invesalius-examples >/dev/null)
fi
dpkg -x "$tmp"/mricron-data_*.deb "$tmp/x"
for f in ch2better.nii.gz ch2.nii.gz; do
  cp "$tmp/x/usr/share/mricron/templates/$f" "data/$f.partial"
  mv "data/$f.partial" "data/$f"
done
# The CT: InVesalius's project holds the volume as matrix.dat (C order: 108 slices of 256x256,
# little-endian int16) with its shape and spacing in main.plist (0.957 x 0.957 x 1.5 mm).
dpkg -x "$tmp"/invesalius-examples_*.deb "$tmp/x"
mkdir -p "$tmp/inv"
tar xzf "$tmp/x/usr/share/doc/invesalius-examples/examples/Cranium.inv3" -C "$tmp/inv"
matrix=$(find "$tmp/inv" -name matrix.dat)
shape=$(grep -A12 '<key>matrix</key>' "$(dirname "$matrix")/main.plist" | tr -d ' \t\r\n')
case "$shape" in
  *'<string>int16</string>'*'<integer>108</integer><integer>256</integer><integer>256</integer>'*) ;;
  *) echo "fetch_data: Cranium.inv3's matrix is not 108x256x256 int16" >&2; exit 1 ;;
esac
cp "$matrix" data/cranium.raw.partial
mv data/cranium.raw.partial data/cranium.raw
cat > data/cranium.nhdr <<'NHDR'
NRRD0004
# Debian's invesalius-examples, Cranium.inv3 (ProMED CT 0051): HU, skin -423.5, bone 200.5
type: int16
dimension: 3
sizes: 256 256 108
spacings: 0.9570312 0.9570312 1.5
encoding: raw
endian: little
data file: cranium.raw
NHDR
echo "fetch_data: data/ch2better.nii.gz data/ch2.nii.gz data/cranium.nhdr (data/cranium.raw)" >&2
