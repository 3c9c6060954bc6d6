#!/usr/bin/env bash
# `fit` and `estimate aps` of two builds side by side (issue 19): per case, command and
# thread count, the median over RUNS runs of wall time, CPU time (user + system) and peak
# resident memory, and whether the two builds' `--json -` outputs are byte-identical
# (each build's output is also compared between one and two threads).
#
# usage: RUNS=3 benches/scripts/estimate_fit_speed.sh BEFORE AFTER [CASE...]
#   BEFORE, AFTER: two ctcal binaries (e.g. a copy of target/release/ctcal built at the
#   commit before the change, and this tree's); CASE: recordings (default: three shared
#   cases with frames).
set -euo pipefail
cd "$(dirname "$0")/../.."
before=$1
after=$2
shift 2
data=../shared/data
cases=("$@")
if [ ${#cases[@]} -eq 0 ]; then
  cases=("$data/real/ijrr_slider_depth_50k" "$data/oracle/dev_hot_pixels"
    "$data/oracle/c_noisy_texture")
fi
runs=${RUNS:-3}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

# median of the numbers on stdin
median() { sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }

# one build, one case, one command, one thread count: RUNS timed runs, the JSON kept
measure() {
  local bin=$1 name=$2 case=$3 threads=$4; shift 4
  : >"$out/times"
  for _ in $(seq "$runs"); do
    /usr/bin/time -f "%e %U %S %M" -o "$out/one" "$bin" --quiet --threads "$threads" "$@" \
      "$case" --json - >"$out/$name.json" 2>/dev/null
    cat "$out/one" >>"$out/times"
  done
  local wall cpu rss
  wall=$(awk '{print $1}' "$out/times" | median)
  cpu=$(awk '{print $2 + $3}' "$out/times" | median)
  rss=$(awk '{print $4 / 1024}' "$out/times" | median)
  printf '%8.2f s %8.2f s %7.0f MB' "$wall" "$cpu" "$rss"
}

printf '%-26s %-13s %2s | %-32s | %-32s | %s\n' case command th \
  "before: wall, CPU, peak RSS" "after: wall, CPU, peak RSS" "JSON"
for case in "${cases[@]}"; do
  label=$(basename "$case")
  for command in "fit" "estimate aps"; do
    tag=${command// /_}
    for threads in 1 2; do
      b=$(measure "$before" "before_${tag}_$threads" "$case" "$threads" $command)
      a=$(measure "$after" "after_${tag}_$threads" "$case" "$threads" $command)
      if cmp -s "$out/before_${tag}_$threads.json" "$out/after_${tag}_$threads.json"; then
        same=identical
      else
        same=DIFFERENT
      fi
      printf '%-26s %-13s %2s | %s | %s | %s\n' "$label" "$command" "$threads" "$b" "$a" "$same"
    done
    for build in before after; do
      cmp -s "$out/${build}_${tag}_1.json" "$out/${build}_${tag}_2.json" ||
        echo "$label $command: $build differs between one and two threads"
    done
  done
done
