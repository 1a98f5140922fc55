#!/usr/bin/env bash
# The viewer end to end on the real MRI: `vdiso serve` on the skull-stripped head, headless
# chromium on the page (tests/browser/e2e.mjs) until the frame is complete, its screenshot
# against `vdiso extract --method sage --camera ... --png` for the same camera; a second page
# following the first (follow mode) shows the same picture and takes over control. Different
# rasterizers, so what must agree is coverage: the pixels the surface covers (--tolerance 255
# compares covered against background only), at least 99.5%; the colour agreement is printed.
#
#   tests/browser/e2e.sh VDISO_BINARY [OUT_DIR]     (ctest runs it; needs VDISO_DATA_DIR)
# With OUT_DIR, the screenshots stay there, with one of the whole page and its overlays
# (viewer_page.png: docs/viewer.png is made this way).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
vdiso=$1
if [ -z "${VDISO_DATA_DIR:-}" ] || [ ! -f "$VDISO_DATA_DIR/ch2better.nii.gz" ]; then
  echo "e2e: VDISO_DATA_DIR has no ch2better.nii.gz (scripts/fetch_data.sh): skipped"
  exit 77
fi
work=$(mktemp -d)
server=""
cleanup() {
  [ -n "$server" ] && kill "$server" 2>/dev/null && wait "$server" 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT
out=${2:-$work}
mkdir -p "$out"

"$vdiso" convert "$VDISO_DATA_DIR/ch2better.nii.gz" "$work/ch2better.vdiso" --quiet
"$vdiso" serve "$work/ch2better.vdiso" --port 0 --iso 40.5 > "$work/serve.log" 2>&1 &
server=$!
url=""
for _ in $(seq 100); do
  url=$(grep -o 'http://[^ ]*' "$work/serve.log" || true)
  [ -n "$url" ] && break
  kill -0 "$server" 2>/dev/null || { cat "$work/serve.log"; exit 1; }
  sleep 0.1
done
[ -n "$url" ] || { echo "e2e: vdiso serve printed no URL"; cat "$work/serve.log"; exit 1; }

# A view of the brain from the front, right and above (volume space of the MRI: origin + index
# * spacing, from its LPS origin (75, 107, -69.5); i runs to the right, j to the front).
echo '{"eye": [338, 736, 170], "target": [150, 199.25, 9.25], "up": [0, 0, 1], "fov": 30}' > "$work/cam.json"
page=()
[ -n "${2:-}" ] && page=(--page "$out/viewer_page.png")
# --timeout: a hang guard, not a speed bound (bench/ measures the viewer): the sanitized build's
# server on 2 busy cores took the session past e2e.mjs's 60 s once (2026-11-29).
node "$here/e2e.mjs" --url "$url" --camera "$work/cam.json" --size 800x800 --out "$out/viewer_frame.png" \
  --follow-out "$out/follower_frame.png" --timeout 180 "${page[@]}" | tee "$work/stats.json"
"$vdiso" extract "$work/ch2better.vdiso" --iso 40.5 --method sage --camera "$work/cam.json" \
  --size 800x800 --png "$out/extract_sage.png" --force --quiet
echo -n "colour (tolerance 24): "
"$vdiso" compare "$out/extract_sage.png" "$out/viewer_frame.png"
echo -n "coverage: "
"$vdiso" compare "$out/extract_sage.png" "$out/viewer_frame.png" --tolerance 255 --min 0.995
echo -n "coverage, the other way: "
"$vdiso" compare "$out/viewer_frame.png" "$out/extract_sage.png" --tolerance 255 --min 0.995
# Follow mode: a second page, opened at the first one's follow link, shows the same picture.
echo -n "follower against leader: "
"$vdiso" compare "$out/viewer_frame.png" "$out/follower_frame.png" --min 0.995
# The server stays up after the browser leaves, and stops cleanly on SIGTERM.
kill -TERM "$server"
wait "$server"
server=""
grep -q "stopped" "$work/serve.log"
echo "e2e: passed"
