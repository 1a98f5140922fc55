# Sourced by the remote benches: start_bucket_server DELAY_MS RATE_MBIT serves data/bench/ with
# the public bucket data/bench/bucket/ on loopback, each request held DELAY_MS before its answer
# and answers capped at RATE_MBIT in all (0: none), and sets `work` (a scratch folder, removed at
# exit), `port`, `remote` (the vdiso options that reach it) and `endpoint` (what the figures are
# measured against, for the benches' footers). Two endpoints, by BUCKET_ENDPOINT:
#   link (default): Debian's nginx serving the files by ranges (tests/remote/start_nginx.py)
#        behind build/bin/vdiso_link_proxy (tests/remote/link_proxy.cpp: the delay and the cap,
#        one compiled thread): its CPU a request is a small fraction of vdiso's, so a figure is
#        vdiso's and the link's.
#   s3:  tests/remote/s3_server.py (Python, the botocore-checked S3 server the tests use), which
#        spends about as much CPU a request as vdiso: on 2 cores the two fight over them.
# The servers die with the script (their stdin is the script's pipe).
start_bucket_server() {
  work=$(mktemp -d)
  trap 'exec 3>&- 4>&-; rm -rf "$work"' EXIT
  local kind=${BUCKET_ENDPOINT:-link}
  if [ "$kind" = s3 ]; then
    exec 3> >(/usr/bin/python3 tests/remote/s3_server.py --root data/bench --public bucket \
                --delay-ms "$1" --rate-mbit "$2" --lifetime 3600 > "$work/port" 2> "$work/server.log")
    endpoint="tests/remote/s3_server.py (Python), $1 ms a request, ${2} Mbit/s (0: no cap)"
  else
    [ -x build/bin/vdiso_link_proxy ] || { echo "build/bin/vdiso_link_proxy is not built" >&2; exit 1; }
    exec 4> >(/usr/bin/python3 tests/remote/start_nginx.py --root data/bench --lifetime 3600 \
                --tmpdir "$work" > "$work/nginx" 2> "$work/nginx.log")
    for _ in $(seq 100); do grep -q PORT "$work/nginx" 2>/dev/null && break; sleep 0.1; done
    local upstream
    upstream=$(awk '/PORT/{print $2}' "$work/nginx")
    exec 3> >(build/bin/vdiso_link_proxy --upstream "$upstream" --delay-ms "$1" --rate-mbit "$2" \
                --lifetime 3600 > "$work/port" 2> "$work/server.log")
    endpoint="nginx behind vdiso_link_proxy, $1 ms a request, ${2} Mbit/s (0: no cap)"
  fi
  for _ in $(seq 100); do grep -q PORT "$work/port" 2>/dev/null && break; sleep 0.1; done
  port=$(awk '/PORT/{print $2}' "$work/port")
  remote=(--no-sign-request --s3-endpoint "http://127.0.0.1:$port")
}
