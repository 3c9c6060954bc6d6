#!/usr/bin/env bash
# `ctcal stats` against `ctcal info` (decoding alone) and against a reference build, on the
# 10 M-event speed inputs (240x180: EVT3 `ev.raw`, event_utils HDF5 `ev.h5`, IJRR text
# `text/`), on one thread and on two: medians of RUNS hyperfine runs (default 7) of the wall
# time, the mean CPU time (user + system; on a loaded machine the wall time of one thread
# mostly measures waiting, its CPU time still the work), plus peak resident memory (GNU
# time). The machine's load is printed before and after, since the cores are shared.
#
# usage: benches/scripts/stats_speed.sh [BEFORE] [AFTER]
#   BEFORE default /work/speed-data/ctcal-before, AFTER default target/release/ctcal;
#   SPEED_DATA (default /work/speed-data) holds the inputs; RUNS the runs per figure.
set -euo pipefail
cd "$(dirname "$0")/../.."
before=${1:-/work/speed-data/ctcal-before}
after=${2:-target/release/ctcal}
speed=${SPEED_DATA:-/work/speed-data}
runs=${RUNS:-7}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "load before: $(uptime)"
for input in "$speed/ev.raw" "$speed/ev.h5" "$speed/text"; do
  for threads in 1 2; do
    hyperfine --runs "$runs" --warmup 1 --style none --export-json "$work/h.json" \
      -n "info" "$after --threads $threads info $input" \
      -n "before stats" "$before --threads $threads stats $input --quiet --json $work/s.json" \
      -n "after stats" "$after --threads $threads stats $input --quiet --json $work/s.json" \
      >/dev/null
    python3 - "$work/h.json" "$input" "$threads" <<'EOF'
import json, sys
runs = {r["command"]: r for r in json.load(open(sys.argv[1]))["results"]}
cpu = {k: r["user"] + r["system"] for k, r in runs.items()}
info = runs["info"]["median"]
line = [f"{sys.argv[2].split('/')[-1]:8} threads {sys.argv[3]}: info {info:.3f} s wall {cpu['info']:.3f} s CPU"]
for name in ("before stats", "after stats"):
    m = runs[name]["median"]
    line.append(f"{name} {m:.3f} s wall ({m / info:.2f}x info, {1e7 / m / 1e6:.0f} M events/s)"
                f" {cpu[name]:.3f} s CPU ({cpu[name] / cpu['info']:.2f}x info)")
print(",\n  ".join(line))
EOF
  done
  for binary in "$before" "$after"; do
    /usr/bin/time -f "  $(basename "$binary") peak %M KB" \
      "$binary" --threads 2 stats "$input" --quiet --json "$work/s.json" >/dev/null
  done
done
echo "load after: $(uptime)"
