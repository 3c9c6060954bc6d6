#!/usr/bin/env bash
# What runs while the pool's other thread waits (issue 19): records one ctcal command on
# two threads with perf (DWARF call graphs, 400 Hz) and prints the serial samples grouped
# by the code that ran them (benches/scripts/serial_share.py).
#
# usage: benches/scripts/serial_share.sh CTCAL ARGS...
#   e.g. benches/scripts/serial_share.sh target/release/ctcal fit ../shared/data/oracle/dev_hot_pixels
set -euo pipefail
bin=$1
shift
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
perf record -q -F 400 --call-graph dwarf,8192 -o "$out/perf.data" \
  "$bin" --quiet --threads 2 "$@" --json /dev/null >/dev/null 2>&1
perf script -i "$out/perf.data" -F tid,time,ip,sym --no-inline 2>/dev/null >"$out/script.txt"
python3 "$(dirname "$0")/serial_share.py" "$out/script.txt"
