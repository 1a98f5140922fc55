#!/usr/bin/env bash
# Remote stores: the distant, normal and closeup views of a generated head read over HTTP with
# a round-trip delay, against the same views read cold from the local disk and against
# downloading the whole store first. The endpoint is bench/bucket_server.sh's (by default nginx
# behind tests/remote/link_proxy.cpp, which holds each request DELAY_MS and caps the answers at
# RATE_MBIT: the delay is in user space, as this kernel has no netem; BUCKET_ENDPOINT=s3 for the
# Python S3 server), a public bucket, no signature.
#
#   bench/remote.sh [SIZE] [DELAY_MS] [ISO] [RATE_MBIT]   (default 512, 20, 600.5 and 0: no
#                                          limit; the store is kept in data/bench/)
#   bench/remote.sh NAME.vdiso DELAY_MS ISO [RATE_MBIT]   a store already in data/bench/bucket/
#
# RATE_MBIT caps the server's bodies at that many Mbit/s in all (1000: a 1 Gbit/s link).
set -euo pipefail
cd "$(dirname "$0")/.."
size=${1:-512}
delay=${2:-20}
vdiso=build/bin/vdiso
source bench/cold_run.sh
mkdir -p data/bench/bucket
iso=${3:-600.5}
rate=${4:-0}
if [[ "$size" == *.vdiso ]]; then name=$size; else name=head$size.vdiso; fi
store=data/bench/bucket/$name
[ -f "$store" ] || $vdiso synth "$store" --kind head --size "$size" --quiet
source bench/bucket_server.sh
start_bucket_server "$delay" "$rate"
url=s3://bucket/$name

number() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$1" "$2"; }

bytes=$(stat -c %s "$store")
# Bytes: a local run's bricks (bytes_read) and all it read from the store (store_bytes: its header
# and the index's parts too), against what the remote run fetched (all of it: store_bytes).
echo "| view | local cold s | local MB read: bricks (all) | remote s | remote MB fetched | remote / local, all bytes | requests | filling a --disk-cache s | again from it s | its requests | whole store at 1 Gbit/s, s |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
# Downloading first: the store's bytes at 1 Gbit/s plus one round trip (loopback is faster).
download=$(python3 -c "print(round($bytes / 125e6 + $delay / 1000, 2))")
# The Python test server hashes the whole object once for its ETag (S3 has it stored): done here
# first, with time for it (a minute for 28 GB).
$vdiso info "$url" "${remote[@]}" --remote-timeout 900 > /dev/null
for view in distant normal closeup; do
  # Remote first, the server's file in its page cache (an object store's own caching and disks
  # are outside what is measured); then the local run, cold.
  # Then a remote run that fills a disk cache (its writes count in its time), and one reading it.
  read -r remote_s _ < <(measure $vdiso extract "$url" "${remote[@]}" --iso "$iso" --method sage --view $view \
                           --size 1024x1024 --stats "$work/remote.json" --quiet --force)
  rm -rf "$work/cache"
  read -r filling_s _ < <(measure $vdiso extract "$url" "${remote[@]}" --iso "$iso" --method sage --view $view \
                           --size 1024x1024 --disk-cache "$work/cache" --quiet --force)
  read -r cached_s _ < <(measure $vdiso extract "$url" "${remote[@]}" --iso "$iso" --method sage --view $view \
                           --size 1024x1024 --stats "$work/cached.json" --disk-cache "$work/cache" --quiet --force)
  drop
  read -r local_s _ < <(measure $vdiso extract "$store" --iso "$iso" --method sage --view $view --size 1024x1024 \
                          --cold --stats "$work/local.json" --quiet --force)
  printf "| %s | %s | %.1f (%.1f) | %s | %.1f | %.2fx | %s | %s | %s | %s | %s |\n" $view "$local_s" \
    "$(python3 -c "print($(number "$work/local.json" bytes_read)/1e6)")" \
    "$(python3 -c "print($(number "$work/local.json" store_bytes)/1e6)")" "$remote_s" \
    "$(python3 -c "print($(number "$work/remote.json" store_bytes)/1e6)")" \
    "$(python3 -c "print($(number "$work/remote.json" store_bytes)/$(number "$work/local.json" store_bytes))")" \
    "$(number "$work/remote.json" remote_requests)" \
    "$filling_s" "$cached_s" "$(number "$work/cached.json" remote_requests)" "$download"
done
echo "($name with levels, sage, 1 frame, against $endpoint, $(nproc) cores; $cold local runs; remote runs with the file in the page cache)"
