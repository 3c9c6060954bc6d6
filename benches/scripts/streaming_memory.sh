#!/usr/bin/env bash
# Streaming check: writes a 200-million-event EVT3 recording (about 1 GB) and reports the
# peak resident memory and wall time of `ctcal stats` on it, on one thread and on all.
#
# usage: benches/scripts/streaming_memory.sh [EVENTS]   (default 200000000)
set -euo pipefail
cd "$(dirname "$0")/../.."
events=${1:-200000000}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cargo build --release --quiet --bin ctcal --example synthetic_recording
target/release/examples/synthetic_recording "$work/big.raw" "$events" 1280x720 2>/dev/null
ls -l "$work/big.raw" | awk '{printf "file: %.2f GB\n", $5 / 1e9}'
for threads in 1 "$(nproc)"; do
  /usr/bin/time -f "threads $threads: %e s wall, %M KB peak resident" \
    target/release/ctcal --threads "$threads" stats "$work/big.raw" --quiet --json "$work/stats.json"
  python3 -c "import json,sys; d=json.load(open('$work/stats.json')); print('  events', d['events'], '-> %.1f M events/s' % (d['events'] / float(sys.argv[1]) / 1e6))" \
    "$(/usr/bin/time -f %e target/release/ctcal --threads "$threads" stats "$work/big.raw" --quiet --json "$work/stats.json" 2>&1)"
done
