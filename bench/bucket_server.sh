# Sourced by the remote benches: start_bucket_server DELAY_MS RATE_MBIT starts
# tests/remote/s3_server.py over data/bench/ with the public bucket data/bench/bucket/, each
# answer's first byte held DELAY_MS and bodies capped at RATE_MBIT (0: none), and sets `work`
# (a scratch folder, removed at exit), `port` and `remote` (the vdiso options that reach it).
# The server dies with the script (its stdin is the script's pipe).
start_bucket_server() {
  work=$(mktemp -d)
  trap 'exec 3>&-; rm -rf "$work"' EXIT
  exec 3> >(/usr/bin/python3 tests/remote/s3_server.py --root data/bench --public bucket \
              --delay-ms "$1" --rate-mbit "$2" --lifetime 3600 > "$work/port" 2> "$work/server.log")
  for _ in $(seq 50); do grep -q PORT "$work/port" 2>/dev/null && break; sleep 0.1; done
  port=$(awk '/PORT/{print $2}' "$work/port")
  remote=(--no-sign-request --s3-endpoint "http://127.0.0.1:$port")
}
