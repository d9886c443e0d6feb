#!/usr/bin/env bash
# rbcd-sim's memory does not grow with the number of frames (issue: long runs):
# 10^5 one-tile frames run under an address-space limit that a per-frame
# record of even 100 bytes would exceed... and the peak (ru_maxrss) stays
# within 8 MiB of a 10^3-frame run's.
#   flat_memory.sh RBCD_SIM WORKDIR SANITIZED(0|1)
set -euo pipefail
sim=$1 dir=$2 sanitized=$3
mkdir -p "$dir"
if [ "$sanitized" != 0 ]; then
  # ASan keeps freed memory in quarantine (256 MB by default) and so grows with
  # any allocation churn: with a small quarantine the peak shows the program's own.
  export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}quarantine_size_mb=1:thread_local_quarantine_size_kb=64"
fi
gen() {   # frames file
  awk -v n="$1" 'BEGIN { print "rbcd-trace 1";
    for (i = 0; i < n; i++) { c = i % 50; printf "frame %d\ntile %d 0 other=20\nf %d 1 100 1 F\nf %d 1 200 1 B\n", i, c, c * 16, c * 16 } }' > "$2"
}
peak_kb() {   # trace -> ru_maxrss of the run, KiB
  /usr/bin/time -f '%M' -o "$dir/rss" "$sim" --trace "$1" -q --stats "$dir/s.json" --frame-stats "$dir/f.jsonl" > /dev/null
  cat "$dir/rss"
}
gen 1000 "$dir/small.rbt"
gen 100000 "$dir/long.rbt"
small=$(peak_kb "$dir/small.rbt")
long=$(peak_kb "$dir/long.rbt")
lines=$(wc -l < "$dir/f.jsonl")
echo "peak memory: 1000 frames ${small} KiB, 100000 frames ${long} KiB; ${lines} frame lines"
[ "$lines" -eq 100000 ] || { echo "FAIL: expected 100000 lines in --frame-stats"; exit 1; }
[ $((long - small)) -le 8192 ] || { echo "FAIL: memory grew by $((long - small)) KiB with 99000 more frames"; exit 1; }
if [ "$sanitized" = 0 ]; then
  # Under a hard limit too (not with ASan, whose shadow memory needs terabytes of address space).
  ( ulimit -v 400000; "$sim" --trace "$dir/long.rbt" -q --stats "$dir/s.json" --frame-stats "$dir/f.jsonl" > /dev/null ) ||
    { echo "FAIL: 100000 frames did not run within 400 MB of address space"; exit 1; }
fi
echo "flat memory: ok"
