#!/usr/bin/env bash
# Identity check for speed work on the simulator: `ctcal simulate` of a reference build
# (BEFORE) and of this tree's build (AFTER) must write byte-identical events, from recorded
# frames and from a scene, with every parameter file in calib/params, on one thread and two.
#
# usage: benches/scripts/compare_simulate.sh [BEFORE] [AFTER]
#   BEFORE default /work/speed-data/ctcal-before, AFTER default target/release/ctcal;
#   DATA (default ../shared/data) holds the frames.
set -uo pipefail
cd "$(dirname "$0")/../.."
before=${1:-/work/speed-data/ctcal-before}
after=${2:-target/release/ctcal}
data=${DATA:-../shared/data}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failed=0
compared=0
for params in calib/params/*.toml; do
  for input in "--frames $data/oracle/b_asym_texture" "--scene calib/scenes/texture_translation.toml"; do
    for threads in 1 2; do
      for binary in "$before" "$after"; do
        rm -rf "$work/$(basename "$binary")"
        # shellcheck disable=SC2086 # the input is an option and its value
        "$binary" --threads "$threads" simulate --quiet --params "$params" $input \
          --out "$work/$(basename "$binary")" >/dev/null 2>&1 ||
          echo "failed: $binary $params $input"
      done
      compared=$((compared + 1))
      if cmp -s "$work/$(basename "$before")/events.txt" "$work/$(basename "$after")/events.txt"; then
        echo "identical ($(wc -l <"$work/$(basename "$after")/events.txt") events): $params $input --threads $threads"
      else
        echo "DIFFERS: $params $input --threads $threads"
        failed=$((failed + 1))
      fi
    done
  done
done
echo "$compared comparisons, $failed differ"
[ "$failed" = 0 ]
