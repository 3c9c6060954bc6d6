#!/usr/bin/env bash
# `ctcal fit CASE` (with frames) of two builds on the cases of the 2026-12-04 notes: per
# case, BEFORE with one then two threads, then AFTER with one then two (each 1 -> 2 thread
# pair back to back), wall, CPU, peak RSS (measure.sh), and whether each JSON is
# byte-identical to BEFORE's one-thread JSON.
#   compare.sh BEFORE AFTER OUTDIR
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
before=$1 after=$2 out=$3
for case in /work/s62/cov9001/cases/case-9030 /work/s62/cov9001/cases/case-9004 \
    /work/s61/cov8001/cases/case-8007; do
    name=$(basename "$case")
    for label in before after; do
        bin=$before
        [ "$label" = after ] && bin=$after
        for threads in 1 2; do
            "$here/measure.sh" "$bin" "$label" "$out" "$threads" "$case"
            if cmp -s "$out/before-t1-$name.json" "$out/$label-t$threads-$name.json"; then
                echo "  $label t$threads $name: JSON identical to before t1"
            else
                echo "  $label t$threads $name: JSON DIFFERS from before t1"
            fi
        done
    done
    echo "  load average: $(cut -d' ' -f1-3 /proc/loadavg)"
done
