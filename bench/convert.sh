#!/usr/bin/env bash
# Conversion throughput and peak memory, cold input, median of N runs.
#
#   bench/convert.sh [SIZE] [RUNS]      default: 1024 3
#   bench/convert.sh 2048 1             the 16 GiB head (needs ~26 GB of disk)
#
# Generates data/headSIZE.raw (u16 CT-like head) if missing, then converts it RUNS times into
# data/headSIZE.vdiso, dropping the page cache before each run (root only; otherwise the input
# is warm and the table says so). Also converts the real MRI (NIfTI, gzip) and generates a
# store straight from `synth`. Prints a Markdown table; bench/log.md records one.
set -euo pipefail
cd "$(dirname "$0")/.."
size=${1:-1024}
runs=${2:-3}
vdiso=build/bin/vdiso
[ -x $vdiso ] || scripts/build.sh
mkdir -p data
raw=data/head$size.raw
[ -f $raw ] || $vdiso synth $raw --kind head --size $size --quiet
bytes=$(stat -c %s $raw)

. bench/cold_run.sh  # drop (the page cache), measure (seconds, peak KB)

echo "| what | input | runs | median s | MB/s (input bytes) | peak RSS MB | peak / input |"
echo "|---|---|---|---|---|---|---|"
row() {  # label input_bytes results...
  local label=$1 in_bytes=$2; shift 2
  printf '%s\n' "$@" | sort -n | awk -v label="$label" -v b="$in_bytes" -v n=$# -v cold="$cold" '
    { s[NR]=$1; m[NR]=$2 } END {
      med = s[int((NR+1)/2)]; peak = 0; for (i in m) if (m[i] > peak) peak = m[i];
      printf "| %s | %.0f MB %s | %d | %.2f | %.0f | %.0f | %.1f%% |\n",
        label, b/1e6, cold, n, med, b/1e6/med, peak/1024, 100*peak*1024/b }'
}

results=()
for _ in $(seq "$runs"); do
  drop
  results+=("$(measure $vdiso convert $raw data/head$size.vdiso --dims $size,$size,$size --type u16 --force)")
done
row "convert raw u16 head ${size}^3" "$bytes" "${results[@]}"

results=()
for _ in $(seq "$runs"); do
  drop
  results+=("$(measure $vdiso synth data/head$size.synth.vdiso --kind head --size $size --force)")
done
row "synth head ${size}^3 into a store" "$bytes" "${results[@]}"
rm -f data/head$size.synth.vdiso

if [ -f data/ch2better.nii.gz ]; then
  mri_bytes=$((301 * 370 * 316))
  results=()
  for _ in $(seq "$runs"); do
    drop
    results+=("$(measure $vdiso convert data/ch2better.nii.gz data/ch2better.vdiso --force)")
  done
  row "convert MRI ch2better.nii.gz (gzip)" "$mri_bytes" "${results[@]}"
fi
