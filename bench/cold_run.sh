# Sourced by the benchmark scripts that time cold runs (bench/convert.sh, bench/readers.sh).
#
# drop: flushes and drops the page cache (root only), setting cold="cold"; otherwise the input
#   stays warm and cold stays "warm", for the table to say so.
# measure CMD...: runs CMD under /usr/bin/time, its output discarded; prints "seconds peak_kb".
#   The peak is the largest of the process and its children (wait4), not their sum.
cold="warm"
drop() {
  sync
  if [ "$(id -u)" -eq 0 ]; then echo 3 > /proc/sys/vm/drop_caches; cold="cold"; fi
}

measure() {
  /usr/bin/time -f "%e %M" -o /tmp/vdiso_bench_time "$@" > /dev/null
  cat /tmp/vdiso_bench_time
}
