#!/usr/bin/env bash
# Wall time and peak memory of `ctcal report` on data_samples (the report issue's budget:
# the sample report in under 2 minutes on 2 cores), on one and on two threads, with the
# time of each stage of each sequence as results.json records it.
#
# usage: benches/scripts/report_time.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release --quiet --bin ctcal
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for threads in 1 2; do
  /usr/bin/time -f "%e %M" -o "$out/time" target/release/ctcal --quiet --threads "$threads" \
    report data_samples --out "$out/report$threads"
  read -r wall kb <"$out/time"
  printf 'threads %d: %6.1f s wall, %4d MB peak resident\n' "$threads" "$wall" $((kb / 1024))
done
python3 - "$out/report2/results.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
for s in r["sequences"]:
    stages = ", ".join(f"{k} {v:.1f} s" for k, v in s["seconds"].items())
    print(f"  {s['name']}: {stages}")
PY
