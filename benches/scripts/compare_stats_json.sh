#!/usr/bin/env bash
# Identity check for speed work: `ctcal stats --json` of a reference build (BEFORE) and of
# this tree's build (AFTER) must be byte-identical on every shared recording, on one thread
# and on two, with and without a pixel selection (--roi takes the kernel's selected path),
# with another timeline window, and on the larger inputs of SPEED_DATA when present.
#
# usage: benches/scripts/compare_stats_json.sh [BEFORE] [AFTER]
#   BEFORE  default /work/speed-data/ctcal-before (a build of the commit before the work)
#   AFTER   default target/release/ctcal
#   DATA (default ../shared/data) and SPEED_DATA (default /work/speed-data) name the inputs.
# Prints one line per comparison and exits non-zero if any output differs.
set -uo pipefail
cd "$(dirname "$0")/../.."
before=${1:-/work/speed-data/ctcal-before}
after=${2:-target/release/ctcal}
data=${DATA:-../shared/data}
speed=${SPEED_DATA:-/work/speed-data}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

inputs=()
for f in "$data"/real/*.raw "$data"/real/*.dat "$data"/real/*.aedat4 \
  "$data"/datasets/*.bag "$data"/datasets/*.h5; do
  [ -e "$f" ] && inputs+=("$f")
done
for d in "$data"/real/*/ "$data"/oracle/*/; do
  [ -e "$d/events.txt" ] && inputs+=("${d%/}")
done
for f in "$speed"/ev.raw "$speed"/ev.h5 "$speed"/text; do
  [ -e "$f" ] && inputs+=("$f")
done

# each variant: the thread count, then options of `stats`
variants=("1" "2" "2 --roi 10,10,200,150" "1 --window 0.002 --support-window 0.005")
failed=0
compared=0
for input in "${inputs[@]}"; do
  for variant in "${variants[@]}"; do
    threads=${variant%% *}
    options=${variant#"$threads"}
    # shellcheck disable=SC2086 # the options are a list of arguments
    "$before" --threads "$threads" stats "$input" $options --quiet --json "$work/before.json" >/dev/null 2>"$work/before.err"
    b=$?
    # shellcheck disable=SC2086
    "$after" --threads "$threads" stats "$input" $options --quiet --json "$work/after.json" >/dev/null 2>"$work/after.err"
    a=$?
    compared=$((compared + 1))
    if [ "$a" != "$b" ]; then
      echo "DIFFERS (exit $b -> $a): $input --threads $variant"
      failed=$((failed + 1))
    elif [ "$b" != 0 ]; then
      if cmp -s "$work/before.err" "$work/after.err"; then
        echo "same error: $input --threads $variant"
      else
        echo "DIFFERS (error text): $input --threads $variant"
        failed=$((failed + 1))
      fi
    elif cmp -s "$work/before.json" "$work/after.json"; then
      echo "identical ($(wc -c <"$work/after.json") bytes): $input --threads $variant"
    else
      echo "DIFFERS: $input --threads $variant"
      diff <(head -c 2000 "$work/before.json") <(head -c 2000 "$work/after.json") | head -5
      failed=$((failed + 1))
    fi
  done
done
echo "$compared comparisons, $failed differ"
[ "$failed" = 0 ]
