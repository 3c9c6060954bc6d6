#!/usr/bin/env bash
# Dataset readers on large files: writes a 50-million-event ROS bag (uncompressed chunks)
# and a DSEC HDF5 file (Blosc/zstd) and reports the wall time and peak resident memory of
# `ctcal stats` on each, on one thread and on all.
#
# usage: benches/scripts/datasets_memory.sh [EVENTS]   (default 50000000)
set -euo pipefail
cd "$(dirname "$0")/../.."
events=${1:-50000000}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cargo build --release --quiet --bin ctcal --example synthetic_recording
target/release/examples/synthetic_recording "$work/big.bag" "$events" 640x480 2>/dev/null
target/release/examples/synthetic_recording "$work/big_dsec.h5" "$events" 640x480 2>/dev/null
for file in big.bag big_dsec.h5; do
  ls -l "$work/$file" | awk -v f="$file" '{printf "%s: %.2f GB\n", f, $5 / 1e9}'
  for threads in 1 "$(nproc)"; do
    /usr/bin/time -f "  threads $threads: %e s wall, %M KB peak resident" \
      target/release/ctcal --threads "$threads" stats "$work/$file" --sensor 640x480 --quiet \
      --json "$work/stats.json" >/dev/null
  done
done
