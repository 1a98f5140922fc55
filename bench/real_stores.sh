#!/usr/bin/env bash
# Makes the stores the real-scan benchmarks read, once: data/bench/{cranium,ch2better,ch2}.vdiso
# from scripts/fetch_data.sh's scans and data/bench/head512.vdiso from a generated 512^3 head
# (u16). Sourced or run from the checkout's root with $vdiso set (default build/bin/vdiso).
set -euo pipefail
vdiso=${vdiso:-${BUILD_DIR:-build}/bin/vdiso}
scripts/fetch_data.sh
mkdir -p data/bench
[ -f data/bench/head512.raw ] || $vdiso synth data/bench/head512.raw --kind head --size 512 --quiet
for s in cranium:data/cranium.nhdr ch2better:data/ch2better.nii.gz ch2:data/ch2.nii.gz head512:data/bench/head512.raw; do
  name=${s%%:*} src=${s#*:}
  [ -f data/bench/$name.vdiso ] && continue
  if [ "$name" = head512 ]; then
    $vdiso convert "$src" data/bench/$name.vdiso --dims 512,512,512 --type u16 --quiet
  else
    $vdiso convert "$src" data/bench/$name.vdiso --quiet
  fi
done
