#!/usr/bin/env bash
# Flame graphs of ctcal's commands on one thread (perf with DWARF call graphs, folded and
# drawn by inferno: `cargo install inferno`), written to benches/flamegraphs/NAME.svg.
# Usage: benches/scripts/flamegraph.sh [CTCAL_BINARY]   (default target/release/ctcal)
set -euo pipefail
cd "$(dirname "$0")/../.."
bin=${1:-target/release/ctcal}
data=../shared/data
out=benches/flamegraphs
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
profile() {
    local name=$1
    shift
    perf record -q -F 250 --call-graph dwarf,32768 -o "$work/$name.data" -- "$bin" "$@" >/dev/null 2>&1
    perf script -i "$work/$name.data" 2>/dev/null | inferno-collapse-perf >"$work/$name.folded"
    inferno-flamegraph --title "ctcal $* (one thread)" --width 1600 --minwidth 2 <"$work/$name.folded" >"$out/$name.svg"
    echo "$out/$name.svg"
}
profile estimate_aps estimate aps "$data/oracle/dev_hot_pixels" --threads 1 --json /dev/null
profile fit fit "$data/oracle/dev_hot_pixels" --threads 1 --json /dev/null
profile stats_evt3 stats "$data/real/evk4_faery_evt3.raw" --threads 1 --json /dev/null
