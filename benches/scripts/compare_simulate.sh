#!/usr/bin/env bash
# Identity check for speed work on the simulator: `ctcal simulate` of a reference build
# (BEFORE) and of this tree's build (AFTER) must write byte-identical events and APS frames,
# from recorded frames and from every scene of calib/scenes (texture, rotation, natural
# image, checkerboard, multi-object), with every parameter file in calib/params, on one
# thread and two.
#
# usage: benches/scripts/compare_simulate.sh [BEFORE] [AFTER]
#   BEFORE default /work/speed-data/ctcal-before, AFTER default target/release/ctcal;
#   DATA (default ../shared/data) holds the frames; SCENES (default calib/scenes/*.toml)
#   the scenes.
set -uo pipefail
cd "$(dirname "$0")/../.."
before=${1:-/work/speed-data/ctcal-before}
after=${2:-target/release/ctcal}
data=${DATA:-../shared/data}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scenes=${SCENES:-$(echo calib/scenes/*.toml)}
inputs=("--frames $data/oracle/b_asym_texture")
for scene in $scenes; do inputs+=("--scene $scene"); done
failed=0
compared=0
for params in calib/params/*.toml; do
  for input in "${inputs[@]}"; do
    for threads in 1 2; do
      for binary in "$before" "$after"; do
        rm -rf "$work/$(basename "$binary")"
        # shellcheck disable=SC2086 # the input is an option and its value
        "$binary" --threads "$threads" simulate --quiet --params "$params" $input \
          --out "$work/$(basename "$binary")" >/dev/null 2>&1 ||
          echo "failed: $binary $params $input"
      done
      compared=$((compared + 1))
      # every file of the output (events, APS frames and their index), not the run's metadata
      if diff -r -q -x '*.json' "$work/$(basename "$before")" "$work/$(basename "$after")" >/dev/null &&
        [ -s "$work/$(basename "$after")/events.txt" ]; then
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
