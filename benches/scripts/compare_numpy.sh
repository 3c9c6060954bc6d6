#!/usr/bin/env bash
# Times `ctcal stats` beside the straightforward NumPy equivalent (stats_numpy.py) on the
# same synthetic recordings: IJRR text, event_utils HDF5 and Prophesee EVT3, and checks that
# both report the same event counts. Needs python3 with numpy and h5py, and hyperfine.
#
# usage: benches/scripts/compare_numpy.sh [EVENTS]   (default 5000000)
set -euo pipefail
cd "$(dirname "$0")/../.."
events=${1:-5000000}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cargo build --release --quiet --bin ctcal --example synthetic_recording
gen=target/release/examples/synthetic_recording
$gen "$work/text" "$events" 1280x720 2>/dev/null
$gen "$work/events.h5" "$events" 1280x720 2>/dev/null
$gen "$work/events.raw" "$events" 1280x720 2>/dev/null
printf '| input | events | ctcal stats (s) | numpy (s) | speed-up | counts agree |\n|---|---|---|---|---|---|\n'
for input in "$work/text" "$work/events.h5" "$work/events.raw"; do
  json_c="$work/c.json"; json_n="$work/n.json"
  hyperfine --warmup 1 --runs 3 --export-json "$json_c" "target/release/ctcal stats $input --quiet --json $work/ours.json" >/dev/null
  hyperfine --runs 1 --export-json "$json_n" "python3 benches/scripts/stats_numpy.py $input > $work/theirs.json" >/dev/null
  python3 - "$input" "$json_c" "$json_n" "$work/ours.json" "$work/theirs.json" "$events" <<'PY'
import json, os, sys
name, jc, jn, ours, theirs, events = sys.argv[1:]
c = json.load(open(jc))["results"][0]["median"]
n = json.load(open(jn))["results"][0]["median"]
o, t = json.load(open(ours)), json.load(open(theirs))
agree = all(o[k] == t[k] for k in ("events", "on_events", "t_first_us", "t_last_us"))
label = {"text": "IJRR text", "events.h5": "HDF5 (event_utils, gzip)", "events.raw": "EVT3"}[os.path.basename(name)]
print(f"| {label} | {int(events):,} | {c:.2f} | {n:.2f} | {n / c:.0f}x | {'yes' if agree else 'NO'} |")
PY
done
