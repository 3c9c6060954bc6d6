#!/usr/bin/env bash
# `estimate screen` of two builds back to back on the cases of the 2026-12-04 notes, one and
# two threads: wall, CPU, peak RSS (measure.sh) and whether the JSON is byte-identical.
#   compare.sh BEFORE AFTER OUTDIR
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
before=$1 after=$2 out=$3
cases=/work/s60/fresh7001/cases
oracle=/work/shared/data/oracle/dev_screen_checker
screen=$here/../../calib/screens/lcd_75hz_gamma2.toml
run() { # THREADS NAME CASE [ARGS...]
    local threads=$1 name=$2
    shift 2
    NAME=$name "$here/measure.sh" "$before" before "$out" "$threads" "$@"
    NAME=$name "$here/measure.sh" "$after" after "$out" "$threads" "$@"
    if cmp -s "$out/before-t$threads-$name.json" "$out/after-t$threads-$name.json"; then
        echo "$name t$threads: JSON identical"
    else
        echo "$name t$threads: JSON DIFFERS"
    fi
}
for threads in 1 2; do
    run "$threads" case-7016 "$cases/case-7016"
    run "$threads" case-7012 "$cases/case-7012"
    run "$threads" case-7020 "$cases/case-7020"
done
run 2 dev_screen_checker "$oracle"
run 2 dev_screen_checker_lcd "$oracle" --screen "$screen" --log-response v2e
