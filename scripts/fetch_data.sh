#!/usr/bin/env bash
# Puts the real default dataset in data/: the MNI "Colin 27" MRI head templates from Debian's
# mricron-data package (ch2better.nii.gz, 301x370x316 u8; ch2.nii.gz, 181x217x181 u8, with
# skin). The package is downloaded and unpacked, not installed.
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p data
if [ -f data/ch2better.nii.gz ] && [ -f data/ch2.nii.gz ]; then exit 0; fi

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
# apt-get download writes into the current directory; make it writable for apt's sandbox user.
chmod 777 "$tmp"
if ! (cd "$tmp" && apt-get download mricron-data >/dev/null 2>&1); then
  $sudo apt-get update -qq
  (cd "$tmp" && apt-get download mricron-data >/dev/null)
fi
dpkg -x "$tmp"/mricron-data_*.deb "$tmp/x"
for f in ch2better.nii.gz ch2.nii.gz; do
  cp "$tmp/x/usr/share/mricron/templates/$f" "data/$f.partial"
  mv "data/$f.partial" "data/$f"
done
echo "fetch_data: data/ch2better.nii.gz data/ch2.nii.gz" >&2
